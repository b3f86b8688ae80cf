#pragma once
// ModbusSimServer is a simulated thermocouple module: a real libmodbus
// server, over TCP on loopback or RTU on a serial line (a socat
// pseudo-terminal in tests), that serves each channel's temperature in
// exactly the register encoding of its ModbusChannel map, so the logger
// cannot tell it from the hardware. Like libmodbus's own test servers
// (unit-test-server, bandit-server) it can inject faults: a burnt-out input,
// a raw code served verbatim, a reply delay, silence (a device that stops
// answering), an exception reply, and over TCP a malformed reply (the correct
// reply with one field altered). It keeps a log of every value it served so
// tests can check that each one reached the run store; faulty replies serve
// no values.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "acquisition/drivers/modbus_device.h"
#include "sim/unique_fd.h"

// libmodbus's register map, declared as <modbus/modbus.h> declares it, so
// that only modbus_server.cc includes the C header.
typedef struct _modbus_mapping_t modbus_mapping_t;

namespace bosfuse::sim {

// Temperature (degC) of `channel` at `t_s` seconds since start; `draw`
// counts the values produced for that channel.
using TemperatureFunction = std::function<double(int channel, double t_s, std::uint64_t draw)>;

// What a ModbusSimServer is set up with.
struct ModbusSimServerOptions {
  acquisition::ModbusEndpoint endpoint;  // TCP: port 0 picks a free port
  std::vector<acquisition::ModbusChannel> channels;
  TemperatureFunction temperature_c;
  // How often served values change; zero: a new value for every request.
  std::chrono::nanoseconds update_period{0};
  // At least this many registers of each kind are served (as a real
  // module serves its whole map), besides those of `channels`.
  int holding_registers = 0;
  int input_registers = 0;
  std::string Validate() const;
};

class ModbusSimServer {
 public:

  struct ServedValue {
    std::int64_t t_ns = 0;
    int channel = 0;
    acquisition::ChannelReading reading;  // what a correct reader decodes
  };

  explicit ModbusSimServer(ModbusSimServerOptions options);
  ~ModbusSimServer();  // stops; never throws
  ModbusSimServer(const ModbusSimServer&) = delete;
  ModbusSimServer& operator=(const ModbusSimServer&) = delete;

  void start();  // listens (TCP) or opens the serial port (RTU); throws
  void stop();
  int port() const { return port_; }  // the bound TCP port
  std::vector<ServedValue> served() const;
  std::int64_t requests_answered() const { return requests_answered_.load(); }
  std::uint64_t draws(int channel) const;  // values produced for `channel` so far

  // A reply that arrives whole but is not the answer to the request: the
  // correct reply to a register read with one field altered.
  enum class MalformedReply {
    kNone,
    kWrongTransactionId,  // the MBAP transaction id of another request
    kWrongByteCount,      // claims one register fewer than it carries
    kWrongFunctionCode,   // a read-input reply to a read-holding request, or back
  };

  // Fault injection; each lasts until changed. Silence wins over an
  // exception, an exception over a malformed reply.
  void set_open_circuit(int channel, bool open);
  void set_raw_override(int channel, std::optional<double> raw);
  void set_reply_delay(std::chrono::milliseconds delay);
  void set_silent(bool silent);
  // Answer every request with Modbus exception `code` (1-11); nullopt: answer.
  void set_exception_reply(std::optional<int> code);
  // Answer every second request with exception `code` and the others
  // correctly, as a module with a loose contact might; nullopt: stop.
  void set_exception_every_other(std::optional<int> code);
  // TCP only (throws std::logic_error on RTU); other requests than register
  // reads are still answered correctly.
  void set_malformed_reply(MalformedReply kind);

 private:
  struct MappingFree {
    void operator()(modbus_mapping_t* mapping) const noexcept;  // modbus_mapping_free
  };
  struct RegisterRead {
    int function = 0;
    int address = 0;
    int count = 0;
  };

  void serve_tcp();
  void serve_rtu();
  void answer(const std::uint8_t* query, int length);
  std::optional<RegisterRead> register_read(const std::uint8_t* query, int length) const;
  void send_malformed(const std::uint8_t* query, const RegisterRead& read, MalformedReply kind);
  void refresh_registers(int function, int address, int count);
  std::vector<std::uint16_t> registers_for(int channel, double t_s, std::uint64_t draw);

  ModbusSimServerOptions options_;
  acquisition::ModbusHandle ctx_;
  std::unique_ptr<modbus_mapping_t, MappingFree> mapping_;
  UniqueFd listen_socket_;
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
  std::optional<int> exception_code_;
  std::optional<int> flapping_code_;  // set_exception_every_other
  std::int64_t flapping_requests_ = 0;
  MalformedReply malformed_ = MalformedReply::kNone;
};

}  // namespace bosfuse::sim

#include "sim/cooling_signal.h"

namespace bosfuse::sim {

// The channels a real module of `profile` exposes for its first `inputs`
// thermocouple inputs, plus its cold junction when it has one.
std::vector<acquisition::ModbusChannel> module_channels(std::string_view profile, int inputs,
                                                        const std::string& tc_type);

// Sizes `options`' register map to the whole map of a real `profile`
// module (every input and the cold junction), so a client reading all of a
// module's registers gets them even when fewer channels are simulated.
void use_profile_register_map(ModbusSimServerOptions& options, std::string_view profile);

// What a simulated module is: its profile, how many thermocouple inputs it
// serves (by default all: both built-in profiles have 8), and the cooling
// curve they read.
struct SimulatedModule {
  std::string profile = "adam-6018";
  int inputs = 8;
  std::string tc_type = "K";
  CoolingSignal signal;
  std::chrono::nanoseconds update_period{0};
};

// Thermocouple channels follow `signal` (each with its own noise stream);
// a cold-junction channel reads the ambient temperature with the same noise.
TemperatureFunction cooling_temperatures(const CoolingSignal& signal,
                                                          const std::vector<acquisition::ModbusChannel>& channels);

ModbusSimServerOptions module_server_options(const SimulatedModule& module, acquisition::ModbusEndpoint endpoint);

}  // namespace bosfuse::sim
