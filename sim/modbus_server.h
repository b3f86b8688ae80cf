#pragma once
// ModbusSimServer is a simulated thermocouple module: a real libmodbus
// server, over TCP on loopback or RTU on a serial line (a socat
// pseudo-terminal in tests), that serves each channel's temperature in
// exactly the register encoding of its ModbusChannel map, so the logger
// cannot tell it from the hardware. Like libmodbus's own test server it can
// inject faults: a burnt-out input, a raw code served verbatim, a reply
// delay, or silence (a device that stops answering). It keeps a log of every
// value it served so tests can check that each one reached the run store.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "acquisition/modbus_device.h"

namespace bosfuse::sim {

class ModbusSimServer {
 public:
  // Temperature (degC) of `channel` at `t_s` seconds since start; `draw`
  // counts the values produced for that channel.
  using TemperatureFunction = std::function<double(int channel, double t_s, std::uint64_t draw)>;

  struct Options {
    acquisition::ModbusEndpoint endpoint;  // TCP: port 0 picks a free port
    std::vector<acquisition::ModbusChannel> channels;
    TemperatureFunction temperature_c;
    // How often served values change; zero: a new value for every request.
    std::chrono::nanoseconds update_period{0};
    std::string Validate() const;
  };

  struct ServedValue {
    std::int64_t t_ns = 0;
    int channel = 0;
    acquisition::ChannelReading reading;  // what a correct reader decodes
  };

  explicit ModbusSimServer(Options options);
  ~ModbusSimServer();  // stops; never throws
  ModbusSimServer(const ModbusSimServer&) = delete;
  ModbusSimServer& operator=(const ModbusSimServer&) = delete;

  void start();  // listens (TCP) or opens the serial port (RTU); throws
  void stop();
  int port() const { return port_; }  // the bound TCP port
  std::vector<ServedValue> served() const;
  std::int64_t requests_answered() const { return requests_answered_.load(); }
  std::uint64_t draws(int channel) const;  // values produced for `channel` so far

  // Fault injection.
  void set_open_circuit(int channel, bool open);
  void set_raw_override(int channel, std::optional<double> raw);
  void set_reply_delay(std::chrono::milliseconds delay);
  void set_silent(bool silent);

 private:
  void serve_tcp();
  void serve_rtu();
  void answer(const std::uint8_t* query, int length);
  void refresh_registers(int function, int address, int count);
  std::vector<std::uint16_t> registers_for(int channel, double t_s, std::uint64_t draw);

  Options options_;
  acquisition::ModbusHandle ctx_;
  modbus_mapping_t* mapping_ = nullptr;
  int listen_socket_ = -1;
  int port_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::atomic<bool> stopping_{false};
  std::atomic<std::int64_t> requests_answered_{0};
  std::thread thread_;

  mutable std::mutex mutex_;
  std::vector<ServedValue> served_;
  std::vector<std::uint64_t> draws_;
  std::map<int, double> raw_overrides_;
  std::vector<bool> open_circuit_;
  std::chrono::milliseconds reply_delay_{0};
  bool silent_ = false;
};

}  // namespace bosfuse::sim

#include "sim/cooling_signal.h"

namespace bosfuse::sim {

// The channels a real module of `profile` exposes for its first `inputs`
// thermocouple inputs, plus its cold junction when it has one.
std::vector<acquisition::ModbusChannel> module_channels(std::string_view profile, int inputs,
                                                        const std::string& tc_type);

// What a simulated module is: its profile, how many thermocouple inputs it
// has, and the cooling curve they read.
struct SimulatedModule {
  std::string profile = "adam-6018";
  int inputs = 4;
  std::string tc_type = "K";
  CoolingSignal signal;
  std::chrono::nanoseconds update_period{0};
};

// Thermocouple channels follow `signal` (each with its own noise stream);
// a cold-junction channel reads the ambient temperature with the same noise.
ModbusSimServer::TemperatureFunction cooling_temperatures(const CoolingSignal& signal,
                                                          const std::vector<acquisition::ModbusChannel>& channels);

ModbusSimServer::Options module_server_options(const SimulatedModule& module, acquisition::ModbusEndpoint endpoint);

}  // namespace bosfuse::sim
