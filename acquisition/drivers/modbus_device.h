#pragma once
// ModbusDevice reads a thermocouple module over Modbus TCP or RTU with
// libmodbus. It groups its channels into as few register reads as possible
// (contiguous blocks of one function code, at most 125 registers each) and
// decodes each channel with its ModbusChannel map. The modbus_t handle lives
// in a unique_ptr, closed and freed on every path.
//
// A failed read says what kind of failure it was (see modbus_failure): a
// device that answered with an exception or a frame that does not fit the
// request is a bad reply on a live link; anything else (no answer, a dropped
// connection) is a transport failure. TCP hosts may be names; they are
// resolved when the logger starts (check_endpoint_resolves) and again at
// every connection.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/drivers/modbus_profile.h"
#include "acquisition/thermocouple_source.h"

// libmodbus's context, declared as <modbus/modbus.h> declares it, so that
// only the wrappers' .cc files include the C header.
typedef struct _modbus modbus_t;

namespace bosfuse::acquisition {

struct ModbusEndpoint {
  ModbusTransport transport = ModbusTransport::kTcp;
  std::string host = "127.0.0.1";  // TCP
  int port = 502;                  // TCP
  std::string serial_port;         // RTU, e.g. /dev/ttyUSB0
  int baud = 9600;                 // RTU
  char parity = 'N';               // RTU: N, E or O
  int data_bits = 8;               // RTU
  int stop_bits = 1;               // RTU
  int unit_id = 1;

  std::string describe() const;  // 127.0.0.1:502 or /dev/ttyUSB0@9600
};

// Throws std::invalid_argument naming the host when a TCP endpoint's host
// does not resolve the way libmodbus will resolve it; RTU endpoints pass.
// A name that never resolves would otherwise be retried for the whole run.
void check_endpoint_resolves(const ModbusEndpoint& endpoint);

// The DeviceError for a libmodbus call that failed with `error` (its errno)
// while doing `what`: an exception reply is kBadReply with the exception
// code as raw; a reply libmodbus rejected (wrong transaction id, function
// code, byte count or length, bad CRC, another unit's reply, a malformed
// exception) is kBadReply without raw; everything else is a transport
// failure (kTimeout).
DeviceError modbus_failure(const std::string& what, int error);

struct ModbusFree {
  void operator()(modbus_t* ctx) const noexcept;  // closes and frees
};
using ModbusHandle = std::unique_ptr<modbus_t, ModbusFree>;

// A libmodbus context for `endpoint` (not yet connected); throws DeviceError.
ModbusHandle make_modbus_context(const ModbusEndpoint& endpoint);

struct RegisterBlock {
  RegisterKind function = RegisterKind::kHolding;
  int address = 0;
  int count = 0;
};

// The reads that cover `channels`: sorted, merged across gaps of at most
// `max_gap` registers, each at most 125 registers (the Modbus limit).
std::vector<RegisterBlock> plan_register_blocks(const std::vector<ModbusChannel>& channels, int max_gap = 8);

class ModbusDevice : public ThermocoupleSource {
 public:
  ModbusDevice(std::string name, std::string profile, ModbusEndpoint endpoint, std::vector<ModbusChannel> channels,
               std::chrono::milliseconds timeout);

  storage::DeviceInfo device_info() const override;
  std::vector<storage::ChannelInfo> channel_infos() const override;
  void connect() override;
  void disconnect() override;
  std::vector<ChannelReading> read() override;

 private:
  std::vector<std::uint16_t> read_block(const RegisterBlock& block);
  void discard_stale_bytes();

  std::string name_;
  std::string profile_;
  ModbusEndpoint endpoint_;
  std::vector<ModbusChannel> channels_;
  std::chrono::milliseconds timeout_;
  std::vector<RegisterBlock> blocks_;
  ModbusHandle ctx_;
  // After a bad reply, bytes of it (or a late answer) may still be on their
  // way; they are discarded before the next request so they cannot be taken
  // for its reply.
  bool stale_bytes_possible_ = false;
};

}  // namespace bosfuse::acquisition
