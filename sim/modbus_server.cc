#include "sim/modbus_server.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <set>
#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::sim {
namespace {

using acquisition::ModbusChannel;
using acquisition::ModbusTransport;
using acquisition::RegisterKind;

constexpr timeval kSelectTimeout{0, 50'000};  // how quickly stop() is noticed

int mapping_size(const std::vector<ModbusChannel>& channels, RegisterKind kind) {
  int size = 0;
  for (const auto& c : channels) {
    if (c.function == kind) size = std::max(size, c.address + c.register_count());
  }
  return size;
}

int bound_port(int socket) {
  sockaddr_in addr{};
  socklen_t length = sizeof addr;
  if (getsockname(socket, reinterpret_cast<sockaddr*>(&addr), &length) != 0) return 0;
  return ntohs(addr.sin_port);
}

}  // namespace

std::string ModbusSimServer::Options::Validate() const {
  if (channels.empty()) return "the simulated module needs at least one channel";
  if (!temperature_c) return "no temperature function";
  for (const auto& c : channels) {
    if (const std::string problem = c.Validate(); !problem.empty()) return c.name + ": " + problem;
  }
  if (update_period.count() < 0) return "update period must not be negative";
  return {};
}

ModbusSimServer::ModbusSimServer(Options options)
    : options_(std::move(options)),
      draws_(options_.channels.size(), 0),
      open_circuit_(options_.channels.size(), false) {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("simulated Modbus module: " + problem);
  }
}

ModbusSimServer::~ModbusSimServer() { stop(); }

void ModbusSimServer::start() {
  stopping_ = false;
  ctx_ = acquisition::make_modbus_context(options_.endpoint);
  mapping_ = modbus_mapping_new(0, 0, mapping_size(options_.channels, RegisterKind::kHolding),
                                mapping_size(options_.channels, RegisterKind::kInput));
  if (!mapping_) throw std::runtime_error("cannot allocate Modbus register map");
  start_ = std::chrono::steady_clock::now();
  if (options_.endpoint.transport == ModbusTransport::kTcp) {
    listen_socket_ = modbus_tcp_listen(ctx_.get(), 8);
    if (listen_socket_ < 0) {
      throw std::runtime_error("cannot listen on " + options_.endpoint.describe() + ": " + modbus_strerror(errno));
    }
    port_ = bound_port(listen_socket_);
    thread_ = std::thread([this] { serve_tcp(); });
  } else {
    if (modbus_connect(ctx_.get()) != 0) {
      throw std::runtime_error("cannot open " + options_.endpoint.describe() + ": " + modbus_strerror(errno));
    }
    thread_ = std::thread([this] { serve_rtu(); });
  }
}

void ModbusSimServer::stop() {
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  if (listen_socket_ >= 0) close(listen_socket_);
  listen_socket_ = -1;
  ctx_.reset();
  if (mapping_) modbus_mapping_free(mapping_);
  mapping_ = nullptr;
}

void ModbusSimServer::serve_tcp() {
  std::set<int> clients;
  while (!stopping_) {
    fd_set ready;
    FD_ZERO(&ready);
    FD_SET(listen_socket_, &ready);
    int highest = listen_socket_;
    for (int fd : clients) {
      FD_SET(fd, &ready);
      highest = std::max(highest, fd);
    }
    timeval timeout = kSelectTimeout;
    if (select(highest + 1, &ready, nullptr, nullptr, &timeout) <= 0) continue;
    if (FD_ISSET(listen_socket_, &ready)) {
      const int client = accept(listen_socket_, nullptr, nullptr);
      if (client >= 0) clients.insert(client);
    }
    for (auto it = clients.begin(); it != clients.end();) {
      if (!FD_ISSET(*it, &ready)) {
        ++it;
        continue;
      }
      modbus_set_socket(ctx_.get(), *it);
      std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
      const int length = modbus_receive(ctx_.get(), query);
      if (length > 0) {
        answer(query, length);
        ++it;
      } else if (length < 0) {  // closed by the client, or garbage
        close(*it);
        it = clients.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (int fd : clients) close(fd);
  modbus_set_socket(ctx_.get(), -1);
}

void ModbusSimServer::serve_rtu() {
  const int fd = modbus_get_socket(ctx_.get());
  while (!stopping_) {
    fd_set ready;
    FD_ZERO(&ready);
    FD_SET(fd, &ready);
    timeval timeout = kSelectTimeout;
    if (select(fd + 1, &ready, nullptr, nullptr, &timeout) <= 0) continue;
    std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
    const int length = modbus_receive(ctx_.get(), query);
    if (length > 0) answer(query, length);
    // length 0: a frame for another unit id; -1: a damaged frame. Both are
    // ignored, as a real module on a shared bus would.
  }
}

void ModbusSimServer::answer(const std::uint8_t* query, int length) {
  std::chrono::milliseconds delay;
  {
    std::lock_guard lock(mutex_);
    if (silent_) return;
    delay = reply_delay_;
  }
  const int header = modbus_get_header_length(ctx_.get());
  if (length >= header + 5) {
    const int function = query[header];
    const int address = (query[header + 1] << 8) | query[header + 2];
    const int count = (query[header + 3] << 8) | query[header + 4];
    refresh_registers(function, address, count);
  }
  if (delay.count() > 0) std::this_thread::sleep_for(delay);
  modbus_reply(ctx_.get(), query, length, mapping_);
  ++requests_answered_;
}

std::vector<std::uint16_t> ModbusSimServer::registers_for(int channel, double t_s, std::uint64_t draw) {
  const ModbusChannel& map = options_.channels[static_cast<std::size_t>(channel)];
  if (auto raw = raw_overrides_.find(channel); raw != raw_overrides_.end()) return map.encode_raw(raw->second);
  if (open_circuit_[static_cast<std::size_t>(channel)] && !map.open_circuit_codes.empty()) {
    return map.encode_raw(map.open_circuit_codes.front());
  }
  return map.encode(options_.temperature_c(channel, t_s, draw));
}

void ModbusSimServer::refresh_registers(int function, int address, int count) {
  const auto kind = static_cast<RegisterKind>(function);
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::int64_t t_ns = acquisition::utc_now_ns();
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < options_.channels.size(); ++i) {
    const ModbusChannel& map = options_.channels[i];
    if (map.function != kind || map.address < address || map.address + map.register_count() > address + count) {
      continue;
    }
    // With an update period, values hold between ticks like a module's
    // conversion cycle; without, each request gets a fresh draw.
    std::uint64_t draw = draws_[i]++;
    double t_s = elapsed_s;
    if (options_.update_period.count() > 0) {
      const double period_s = std::chrono::duration<double>(options_.update_period).count();
      draw = static_cast<std::uint64_t>(std::floor(elapsed_s / period_s));
      t_s = static_cast<double>(draw) * period_s;
    }
    const std::vector<std::uint16_t> registers = registers_for(static_cast<int>(i), t_s, draw);
    std::uint16_t* table = kind == RegisterKind::kHolding ? mapping_->tab_registers : mapping_->tab_input_registers;
    std::copy(registers.begin(), registers.end(), table + map.address);
    served_.push_back({t_ns, static_cast<int>(i), map.decode(registers)});
  }
}

std::uint64_t ModbusSimServer::draws(int channel) const {
  std::lock_guard lock(mutex_);
  return draws_.at(static_cast<std::size_t>(channel));
}

std::vector<ModbusSimServer::ServedValue> ModbusSimServer::served() const {
  std::lock_guard lock(mutex_);
  return served_;
}

void ModbusSimServer::set_open_circuit(int channel, bool open) {
  std::lock_guard lock(mutex_);
  open_circuit_.at(static_cast<std::size_t>(channel)) = open;
}

void ModbusSimServer::set_raw_override(int channel, std::optional<double> raw) {
  std::lock_guard lock(mutex_);
  if (raw) {
    raw_overrides_[channel] = *raw;
  } else {
    raw_overrides_.erase(channel);
  }
}

void ModbusSimServer::set_reply_delay(std::chrono::milliseconds delay) {
  std::lock_guard lock(mutex_);
  reply_delay_ = delay;
}

void ModbusSimServer::set_silent(bool silent) {
  std::lock_guard lock(mutex_);
  silent_ = silent;
}

}  // namespace bosfuse::sim

namespace bosfuse::sim {

std::vector<acquisition::ModbusChannel> module_channels(std::string_view profile, int inputs,
                                                        const std::string& tc_type) {
  const acquisition::ModbusProfile* p = acquisition::find_modbus_profile(profile);
  if (!p || p->input_count == 0) {
    throw std::invalid_argument("no simulated module for profile '" + std::string(profile) + "'");
  }
  std::vector<acquisition::ModbusChannel> channels;
  for (int i = 0; i < inputs; ++i) {
    channels.push_back(acquisition::profile_input_channel(profile, i, tc_type));
    channels.back().name = "tc" + std::to_string(i);
  }
  if (p->has_cold_junction) {
    channels.push_back(acquisition::profile_cold_junction_channel(profile));
    channels.back().name = "cold-junction";
  }
  return channels;
}

ModbusSimServer::TemperatureFunction cooling_temperatures(const CoolingSignal& signal,
                                                          const std::vector<acquisition::ModbusChannel>& channels) {
  if (const std::string problem = signal.Validate(); !problem.empty()) {
    throw std::invalid_argument("cooling signal: " + problem);
  }
  std::vector<bool> is_cold_junction;
  for (const auto& c : channels) is_cold_junction.push_back(c.kind == "cold-junction");
  return [signal, is_cold_junction](int channel, double t_s, std::uint64_t draw) {
    if (is_cold_junction.at(static_cast<std::size_t>(channel))) {
      return signal.ambient_c + signal.noise_c * hashed_normal(signal.seed, 1000u + channel, draw);
    }
    return signal.sample_c(t_s, channel, draw);
  };
}

ModbusSimServer::Options module_server_options(const SimulatedModule& module, acquisition::ModbusEndpoint endpoint) {
  ModbusSimServer::Options options;
  options.endpoint = std::move(endpoint);
  options.channels = module_channels(module.profile, module.inputs, module.tc_type);
  options.temperature_c = cooling_temperatures(module.signal, options.channels);
  options.update_period = module.update_period;
  return options;
}

}  // namespace bosfuse::sim
