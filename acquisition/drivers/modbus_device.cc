#include "acquisition/drivers/modbus_device.h"

#include <modbus/modbus.h>
#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <utility>

namespace bosfuse::acquisition {
namespace {

constexpr int kMaxRegistersPerRead = 125;

std::string modbus_error(const std::string& what) { return what + ": " + modbus_strerror(errno); }

bool is_exception_reply(int error) {
  return error > MODBUS_ENOBASE && error < MODBUS_ENOBASE + MODBUS_EXCEPTION_MAX;
}

// The errors libmodbus raises for a reply it received but will not accept.
bool is_rejected_reply(int error) {
  return error == EMBBADDATA || error == EMBBADCRC || error == EMBBADSLAVE || error == EMBBADEXC ||
         error == EMBUNKEXC || error == EMBMDATA;
}

struct AddrinfoFree {
  void operator()(addrinfo* list) const noexcept { freeaddrinfo(list); }
};

// The same lookup libmodbus's modbus_tcp_pi connect makes, so a name that
// passes here is one libmodbus can connect to. Returns 0 or a getaddrinfo
// error code.
int resolve(const ModbusEndpoint& endpoint) {
  addrinfo hints{};
  hints.ai_flags = AI_ADDRCONFIG;
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* raw = nullptr;
  const int result = getaddrinfo(endpoint.host.c_str(), std::to_string(endpoint.port).c_str(), &hints, &raw);
  const std::unique_ptr<addrinfo, AddrinfoFree> list(raw);
  return result;
}

std::string resolve_failure(const ModbusEndpoint& endpoint, int result) {
  return "cannot resolve host \"" + endpoint.host + "\": " + gai_strerror(result);
}

bool same_block(const RegisterBlock& block, const ModbusChannel& channel, int max_gap) {
  const int end = channel.address + channel.register_count();
  return channel.function == block.function && channel.address <= block.address + block.count + max_gap &&
         end - block.address <= kMaxRegistersPerRead;
}

}  // namespace

void ModbusFree::operator()(modbus_t* ctx) const noexcept {
  modbus_close(ctx);
  modbus_free(ctx);
}

std::string ModbusEndpoint::describe() const {
  if (transport == ModbusTransport::kTcp) return host + ":" + std::to_string(port);
  return serial_port + "@" + std::to_string(baud);
}

void check_endpoint_resolves(const ModbusEndpoint& endpoint) {
  if (endpoint.transport != ModbusTransport::kTcp) return;
  if (const int result = resolve(endpoint); result != 0) {
    throw std::invalid_argument(resolve_failure(endpoint, result));
  }
}

DeviceError modbus_failure(const std::string& what, int error) {
  const std::string message = what + ": " + modbus_strerror(error);
  if (is_exception_reply(error)) {
    const int code = error - MODBUS_ENOBASE;
    return DeviceError(what + ": Modbus exception " + std::to_string(code) + " (" + modbus_strerror(error) + ")",
                       storage::SampleStatus::kBadReply, code);
  }
  if (is_rejected_reply(error)) return DeviceError(message, storage::SampleStatus::kBadReply);
  return DeviceError(message);
}

// TCP goes through libmodbus's protocol-independent ("pi") back end, the
// one that resolves host names; plain modbus_new_tcp takes IPv4 addresses only.
ModbusHandle make_modbus_context(const ModbusEndpoint& endpoint) {
  modbus_t* raw = endpoint.transport == ModbusTransport::kTcp
                      ? modbus_new_tcp_pi(endpoint.host.c_str(), std::to_string(endpoint.port).c_str())
                      : modbus_new_rtu(endpoint.serial_port.c_str(), endpoint.baud, endpoint.parity, endpoint.data_bits,
                                       endpoint.stop_bits);
  if (!raw) throw DeviceError(modbus_error("cannot create Modbus context for " + endpoint.describe()));
  ModbusHandle ctx(raw);
  if (modbus_set_slave(raw, endpoint.unit_id) != 0) {
    throw DeviceError(modbus_error("invalid unit id " + std::to_string(endpoint.unit_id)));
  }
  return ctx;
}

std::vector<RegisterBlock> plan_register_blocks(const std::vector<ModbusChannel>& channels, int max_gap) {
  std::vector<const ModbusChannel*> sorted;
  for (const auto& channel : channels) sorted.push_back(&channel);
  std::sort(sorted.begin(), sorted.end(), [](const ModbusChannel* a, const ModbusChannel* b) {
    return std::pair(a->function, a->address) < std::pair(b->function, b->address);
  });
  std::vector<RegisterBlock> blocks;
  for (const ModbusChannel* channel : sorted) {
    const int end = channel->address + channel->register_count();
    if (!blocks.empty() && same_block(blocks.back(), *channel, max_gap)) {
      blocks.back().count = std::max(blocks.back().count, end - blocks.back().address);
    } else {
      blocks.push_back({channel->function, channel->address, channel->register_count()});
    }
  }
  return blocks;
}

ModbusDevice::ModbusDevice(std::string name, std::string profile, ModbusEndpoint endpoint,
                           std::vector<ModbusChannel> channels, std::chrono::milliseconds timeout)
    : name_(std::move(name)),
      profile_(std::move(profile)),
      endpoint_(std::move(endpoint)),
      channels_(std::move(channels)),
      timeout_(timeout),
      blocks_(plan_register_blocks(channels_)) {}

storage::DeviceInfo ModbusDevice::device_info() const {
  const char* kind = endpoint_.transport == ModbusTransport::kTcp ? "modbus-tcp" : "modbus-rtu";
  return {0, name_, kind, profile_, endpoint_.describe()};
}

std::vector<storage::ChannelInfo> ModbusDevice::channel_infos() const {
  std::vector<storage::ChannelInfo> infos;
  for (const auto& c : channels_) {
    infos.push_back({0, 0, c.name, c.kind, c.unit, c.tc_type, c.image_x_px, c.image_y_px, c.stored_resolution()});
  }
  return infos;
}

void ModbusDevice::connect() {
  ctx_ = make_modbus_context(endpoint_);
  const auto micros = std::chrono::duration_cast<std::chrono::microseconds>(timeout_).count();
  modbus_set_response_timeout(ctx_.get(), static_cast<std::uint32_t>(micros / 1'000'000),
                              static_cast<std::uint32_t>(micros % 1'000'000));
  if (modbus_connect(ctx_.get()) != 0) {
    std::string message = modbus_error("cannot connect to " + endpoint_.describe());
    // libmodbus reports a failed lookup as "Connection refused"; say what it was.
    if (endpoint_.transport == ModbusTransport::kTcp) {
      if (const int result = resolve(endpoint_); result != 0) message = resolve_failure(endpoint_, result);
    }
    ctx_.reset();
    throw DeviceError(message);
  }
  // A serial line may still hold the tail of an answer to a request made
  // before the reconnection.
  modbus_flush(ctx_.get());
  stale_bytes_possible_ = false;
}

void ModbusDevice::disconnect() { ctx_.reset(); }

// libmodbus reads a reply by the lengths its header announces and leaves the
// rest in the socket (a byte count that claims too little leaves the last
// registers behind); only with MODBUS_ERROR_RECOVERY_PROTOCOL does it flush,
// and then after sleeping a whole response timeout. Flushing at once and
// again before the next request costs nothing and keeps such a tail, or an
// answer that arrives after its time-out, out of the next reply.
void ModbusDevice::discard_stale_bytes() {
  modbus_flush(ctx_.get());
  stale_bytes_possible_ = true;
}

std::vector<std::uint16_t> ModbusDevice::read_block(const RegisterBlock& block) {
  std::vector<std::uint16_t> registers(static_cast<std::size_t>(block.count));
  const int n = block.function == RegisterKind::kHolding
                    ? modbus_read_registers(ctx_.get(), block.address, block.count, registers.data())
                    : modbus_read_input_registers(ctx_.get(), block.address, block.count, registers.data());
  if (n != block.count) {
    const int error = errno;
    DeviceError failure = modbus_failure("reading " + std::to_string(block.count) + " registers at " +
                                             std::to_string(block.address) + " from " + endpoint_.describe(),
                                         error);
    discard_stale_bytes();
    throw failure;
  }
  return registers;
}

std::vector<ChannelReading> ModbusDevice::read() {
  if (!ctx_) throw DeviceError("not connected to " + endpoint_.describe());
  if (std::exchange(stale_bytes_possible_, false)) modbus_flush(ctx_.get());
  std::vector<std::vector<std::uint16_t>> block_registers;
  for (const RegisterBlock& block : blocks_) block_registers.push_back(read_block(block));
  std::vector<ChannelReading> readings;
  for (const ModbusChannel& channel : channels_) {
    for (std::size_t b = 0; b < blocks_.size(); ++b) {
      const RegisterBlock& block = blocks_[b];
      const int offset = channel.address - block.address;
      if (channel.function != block.function || offset < 0 || offset + channel.register_count() > block.count) {
        continue;
      }
      readings.push_back(channel.decode(std::span(block_registers[b]).subspan(static_cast<std::size_t>(offset))));
      break;
    }
  }
  return readings;
}

}  // namespace bosfuse::acquisition
