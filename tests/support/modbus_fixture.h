#pragma once
// Helpers shared by the Modbus integration tests: a simulated module on
// loopback, an experiment file for it, and a logger run of bounded length.

#include <atomic>
#include <chrono>
#include <map>
#include <string>

#include "acquisition/clock.h"
#include "acquisition/config/experiment_config.h"
#include "acquisition/logger.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"

namespace bosfuse::testing {

using namespace std::chrono_literals;
using acquisition::ModbusEndpoint;
using acquisition::ModbusTransport;

inline storage::RunInfo run_info(const std::string& config_text) {
  return {0, "test-run", acquisition::utc_now_ns(), std::nullopt, config_text, storage::RunStatus::kRunning, 1.0, std::nullopt};
}

inline sim::ModbusSimServerOptions module_options(const std::string& profile, int inputs, ModbusEndpoint endpoint) {
  return sim::module_server_options({profile, inputs, "K", sim::CoolingSignal{22.0, 85.0, 0.2, 0.3, 7}, {}},
                                    std::move(endpoint));
}

inline ModbusEndpoint loopback_tcp(int port = 0) {
  ModbusEndpoint endpoint;
  endpoint.host = "127.0.0.1";
  endpoint.port = port;
  return endpoint;
}

inline acquisition::Logger::Summary log_for(storage::RunStore& store, const acquisition::ExperimentConfig& config,
                                            std::chrono::milliseconds duration,
                                            std::function<void(const std::string&)> on_progress = {},
                                            std::function<void(const std::string&)> on_alarm = {}) {
  acquisition::LoggerOptions options;
  options.duration = duration;
  options.writer.flush_interval = 50ms;
  options.backoff_initial = 50ms;
  options.backoff_max = 200ms;
  options.on_progress = std::move(on_progress);
  options.progress_interval = 200ms;
  options.on_alarm = std::move(on_alarm);
  acquisition::Logger logger(store, options);
  logger.add_devices(config);
  std::atomic<bool> stop{false};
  return logger.run(stop);
}

// Channels `<channel_prefix>0`, `<channel_prefix>1`, ...: give each device of
// one file its own prefix, since channel names are unique across devices.
inline std::string tcp_device_toml(const std::string& name, int port, int inputs, double period_s,
                                   const std::string& channel_prefix = "tc") {
  std::string text = "[[devices]]\nname = \"" + name +
                     "\"\nprofile = \"adam-6018\"\nhost = \"127.0.0.1\"\nport = " + std::to_string(port) +
                     "\npoll_period_s = " + std::to_string(period_s) + "\ntimeout_s = 0.5\n";
  for (int i = 0; i < inputs; ++i) {
    text += "[[devices.channels]]\nname = \"" + channel_prefix + std::to_string(i) +
            "\"\ninput = " + std::to_string(i) + "\n";
  }
  return text;
}

inline std::map<std::string, std::vector<storage::Sample>> samples_by_channel(const storage::RunStore& store) {
  std::map<std::string, std::vector<storage::Sample>> out;
  for (const auto& channel : store.channels()) out[channel.name] = store.read_samples(channel.id);
  return out;
}

}  // namespace bosfuse::testing

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

namespace bosfuse::testing {

// A loopback TCP port nothing listens on (free when this returns).
inline int unused_loopback_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t length = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &length);
  close(fd);
  return ntohs(addr.sin_port);
}

// A device's events but "skipped", which a loaded machine can cause at any
// time (tests of skipped polls read those events themselves).
inline std::vector<std::string> event_kinds(const storage::RunStore& store, std::int64_t device_id) {
  std::vector<std::string> kinds;
  for (const auto& e : store.events()) {
    if (e.device_id == device_id && e.kind != "skipped") kinds.push_back(e.kind);
  }
  return kinds;
}

inline std::int64_t device_id(const storage::RunStore& store, const std::string& name) {
  for (const auto& d : store.devices()) {
    if (d.name == name) return d.id;
  }
  return -1;
}

}  // namespace bosfuse::testing
