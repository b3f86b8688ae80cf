#include "sim/modbus_server.h"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <spdlog/spdlog.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
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
  sockaddr_storage addr{};
  socklen_t length = sizeof addr;
  if (getsockname(socket, reinterpret_cast<sockaddr*>(&addr), &length) != 0) return 0;
  if (addr.ss_family == AF_INET6) return ntohs(reinterpret_cast<const sockaddr_in6&>(addr).sin6_port);
  return ntohs(reinterpret_cast<const sockaddr_in&>(addr).sin_port);
}

constexpr int kTcpHeaderLength = 7;  // MBAP: transaction id, protocol id, length, unit id

}  // namespace

void ModbusSimServer::MappingFree::operator()(modbus_mapping_t* mapping) const noexcept {
  modbus_mapping_free(mapping);
}

std::string ModbusSimServerOptions::Validate() const {
  if (channels.empty()) return "the simulated module needs at least one channel";
  if (!temperature_c) return "no temperature function";
  for (const auto& c : channels) {
    if (const std::string problem = c.Validate(); !problem.empty()) return c.name + ": " + problem;
  }
  if (update_period.count() < 0) return "update period must not be negative";
  if (holding_registers < 0 || input_registers < 0) return "register counts must not be negative";
  return {};
}

ModbusSimServer::ModbusSimServer(ModbusSimServerOptions options)
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
  mapping_.reset(
      modbus_mapping_new(0, 0, std::max(options_.holding_registers, mapping_size(options_.channels, RegisterKind::kHolding)),
                         std::max(options_.input_registers, mapping_size(options_.channels, RegisterKind::kInput))));
  if (!mapping_) throw std::runtime_error("cannot allocate Modbus register map");
  start_ = std::chrono::steady_clock::now();
  if (options_.endpoint.transport == ModbusTransport::kTcp) {
    // The TCP context is libmodbus's "pi" one (see make_modbus_context),
    // whose listen is modbus_tcp_pi_listen.
    listen_socket_.reset(modbus_tcp_pi_listen(ctx_.get(), 8));
    if (!listen_socket_) {
      throw std::runtime_error("cannot listen on " + options_.endpoint.describe() + ": " + modbus_strerror(errno));
    }
    port_ = bound_port(listen_socket_.get());
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
  listen_socket_.reset();
  ctx_.reset();
  mapping_.reset();
}

void ModbusSimServer::serve_tcp() {
  std::vector<UniqueFd> clients;
  while (!stopping_) {
    fd_set ready;
    FD_ZERO(&ready);
    FD_SET(listen_socket_.get(), &ready);
    int highest = listen_socket_.get();
    for (const UniqueFd& client : clients) {
      FD_SET(client.get(), &ready);
      highest = std::max(highest, client.get());
    }
    timeval timeout = kSelectTimeout;
    if (select(highest + 1, &ready, nullptr, nullptr, &timeout) <= 0) continue;
    for (auto it = clients.begin(); it != clients.end();) {
      if (!FD_ISSET(it->get(), &ready)) {
        ++it;
        continue;
      }
      modbus_set_socket(ctx_.get(), it->get());
      std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
      const int length = modbus_receive(ctx_.get(), query);
      if (length > 0) answer(query, length);
      // Below zero: closed by the client, or garbage.
      it = length < 0 ? clients.erase(it) : it + 1;
    }
    if (FD_ISSET(listen_socket_.get(), &ready)) {
      UniqueFd client(accept(listen_socket_.get(), nullptr, nullptr));
      if (client) clients.push_back(std::move(client));
    }
  }
  // The clients close themselves; the context must not close one again.
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
  std::optional<int> exception_code;
  MalformedReply malformed;
  {
    std::lock_guard lock(mutex_);
    if (silent_) return;
    delay = reply_delay_;
    exception_code = exception_code_;
    if (!exception_code && flapping_code_ && flapping_requests_++ % 2 == 1) exception_code = flapping_code_;
    malformed = malformed_;
  }
  const std::optional<RegisterRead> read = register_read(query, length);
  const bool send_malformed_reply = !exception_code && malformed != MalformedReply::kNone && read;
  if (read && !exception_code && !send_malformed_reply) refresh_registers(read->function, read->address, read->count);
  if (delay.count() > 0) std::this_thread::sleep_for(delay);
  if (exception_code) {
    modbus_reply_exception(ctx_.get(), query, static_cast<unsigned>(*exception_code));
  } else if (send_malformed_reply) {
    send_malformed(query, *read, malformed);
  } else {
    modbus_reply(ctx_.get(), query, length, mapping_.get());
  }
  ++requests_answered_;
}

// A read of holding or input registers the map can answer, or nullopt.
std::optional<ModbusSimServer::RegisterRead> ModbusSimServer::register_read(const std::uint8_t* query,
                                                                             int length) const {
  const int header = modbus_get_header_length(ctx_.get());
  if (length < header + 5) return std::nullopt;
  const RegisterRead read{query[header], (query[header + 1] << 8) | query[header + 2],
                          (query[header + 3] << 8) | query[header + 4]};
  if (read.function != MODBUS_FC_READ_HOLDING_REGISTERS && read.function != MODBUS_FC_READ_INPUT_REGISTERS) {
    return std::nullopt;
  }
  const int size = read.function == MODBUS_FC_READ_HOLDING_REGISTERS ? mapping_->nb_registers
                                                                      : mapping_->nb_input_registers;
  if (read.count < 1 || read.count > MODBUS_MAX_READ_REGISTERS || read.address + read.count > size) {
    return std::nullopt;
  }
  return read;
}

// libmodbus only sends correct replies, so the malformed one is composed
// here: the reply modbus_reply would send for `read`, with one field changed.
void ModbusSimServer::send_malformed(const std::uint8_t* query, const RegisterRead& read, MalformedReply kind) {
  const std::uint16_t* table = read.function == MODBUS_FC_READ_HOLDING_REGISTERS ? mapping_->tab_registers
                                                                                   : mapping_->tab_input_registers;
  const int pdu_length = 3 + 2 * read.count;  // unit id, function code, byte count, data
  std::vector<std::uint8_t> adu = {query[0],
                                   query[1],
                                   0,
                                   0,
                                   static_cast<std::uint8_t>(pdu_length >> 8),
                                   static_cast<std::uint8_t>(pdu_length & 0xFF),
                                   query[kTcpHeaderLength - 1],
                                   static_cast<std::uint8_t>(read.function),
                                   static_cast<std::uint8_t>(2 * read.count)};
  for (int i = 0; i < read.count; ++i) {
    adu.push_back(static_cast<std::uint8_t>(table[read.address + i] >> 8));
    adu.push_back(static_cast<std::uint8_t>(table[read.address + i] & 0xFF));
  }
  switch (kind) {
    case MalformedReply::kWrongTransactionId:
      adu[1] = static_cast<std::uint8_t>(adu[1] + 1);
      if (adu[1] == 0) adu[0] = static_cast<std::uint8_t>(adu[0] + 1);
      break;
    case MalformedReply::kWrongByteCount:
      adu[8] = static_cast<std::uint8_t>(adu[8] - 2);
      break;
    case MalformedReply::kWrongFunctionCode:
      adu[7] = read.function == MODBUS_FC_READ_HOLDING_REGISTERS ? MODBUS_FC_READ_INPUT_REGISTERS
                                                                  : MODBUS_FC_READ_HOLDING_REGISTERS;
      break;
    case MalformedReply::kNone:
      break;
  }
  // One send, so the client finds the whole frame (and any bytes it does
  // not expect) in its socket at once, as with a real module.
  if (send(modbus_get_socket(ctx_.get()), adu.data(), adu.size(), MSG_NOSIGNAL) < 0) {
    spdlog::debug("simulated module: cannot send a malformed reply: {}", std::strerror(errno));
  }
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

void ModbusSimServer::set_exception_reply(std::optional<int> code) {
  if (code && (*code < 1 || *code >= MODBUS_EXCEPTION_MAX)) {
    throw std::invalid_argument("Modbus exception codes are 1.." + std::to_string(MODBUS_EXCEPTION_MAX - 1) +
                                ", not " + std::to_string(*code));
  }
  std::lock_guard lock(mutex_);
  exception_code_ = code;
}

void ModbusSimServer::set_exception_every_other(std::optional<int> code) {
  if (code && (*code < 1 || *code >= MODBUS_EXCEPTION_MAX)) throw std::invalid_argument("not a Modbus exception code");
  std::lock_guard lock(mutex_);
  flapping_code_ = code;
  flapping_requests_ = 0;
}

void ModbusSimServer::set_malformed_reply(MalformedReply kind) {
  if (kind != MalformedReply::kNone && options_.endpoint.transport != ModbusTransport::kTcp) {
    throw std::logic_error("malformed replies are simulated over Modbus TCP only");
  }
  std::lock_guard lock(mutex_);
  malformed_ = kind;
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

TemperatureFunction cooling_temperatures(const CoolingSignal& signal,
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

void use_profile_register_map(ModbusSimServerOptions& options, std::string_view profile) {
  const acquisition::ModbusProfile* p = acquisition::find_modbus_profile(profile);
  if (!p || p->input_count == 0) return;  // generic: no map of its own
  const auto all = module_channels(profile, p->input_count, "K");
  options.holding_registers = std::max(options.holding_registers, mapping_size(all, RegisterKind::kHolding));
  options.input_registers = std::max(options.input_registers, mapping_size(all, RegisterKind::kInput));
}

ModbusSimServerOptions module_server_options(const SimulatedModule& module, acquisition::ModbusEndpoint endpoint) {
  ModbusSimServerOptions options;
  options.endpoint = std::move(endpoint);
  options.channels = module_channels(module.profile, module.inputs, module.tc_type);
  use_profile_register_map(options, module.profile);
  options.temperature_c = cooling_temperatures(module.signal, options.channels);
  options.update_period = module.update_period;
  return options;
}

}  // namespace bosfuse::sim
