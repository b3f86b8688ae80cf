// Register and Modbus reply decoding. The input is split by
// FuzzedDataProvider into up to 16 Modbus channel configurations (function
// code, address, data type, word order, scale/offset or a linear mapping,
// open-circuit and out-of-range codes, valid range; only those Validate()
// accepts, as the experiment file would) and the register words a device
// answers with. The channels are planned into register blocks with
// plan_register_blocks() and each block's reply is decoded per channel
// exactly as ModbusDevice::read() does (libmodbus hands the reply over as
// host-order words; there is no separate reply decoder in bosfuse).
// Invariants: every block stays within the Modbus limits (1..125 registers,
// addresses 0..65535) and every channel lies inside one block; a reading's
// status is a valid SampleStatus; a reading has a value exactly when it is
// kOk, and that value is finite and inside the channel's valid range;
// non-finite raw values are never kOk, and an
// open-circuit or out-of-range code is never kOk; decode_registers followed by
// encode_registers gives back the same words for every integer type and
// for float32 when the value is not a NaN.

#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "acquisition/drivers/modbus_channel.h"
#include "acquisition/drivers/modbus_device.h"
#include "acquisition/drivers/register_codec.h"
#include "fuzz/fuzz_support.h"

using namespace bosfuse::acquisition;
using bosfuse::storage::SampleStatus;

namespace {

std::optional<double> maybe_number(FuzzedDataProvider& in) {
  if (!in.ConsumeBool()) return std::nullopt;
  return in.ConsumeFloatingPointInRange<double>(-1e9, 1e9);
}

ModbusChannel make_channel(FuzzedDataProvider& in, int index) {
  ModbusChannel c;
  c.name = "ch" + std::to_string(index);
  c.function = in.ConsumeBool() ? RegisterKind::kHolding : RegisterKind::kInput;
  c.address = in.ConsumeIntegralInRange<int>(0, 0xFFFF);
  c.type = static_cast<DataType>(in.ConsumeIntegralInRange<int>(0, 4));
  c.order = static_cast<WordOrder>(in.ConsumeIntegralInRange<int>(0, 3));
  // Magnitudes a lab file can mean (|scale| 1e-6..1e6, integer raw end
  // points): with them every finite raw value maps to a finite value. (An
  // absurd scale such as 1e308 overflows to an infinite "ok" value; see
  // docs/RELIABILITY.md.)
  c.scale = (in.ConsumeBool() ? 1 : -1) * in.ConsumeFloatingPointInRange<double>(1e-6, 1e6);
  c.offset = in.ConsumeFloatingPointInRange<double>(-1e6, 1e6);
  if (in.ConsumeBool()) {
    c.linear = LinearMapping{static_cast<double>(in.ConsumeIntegral<std::int32_t>()),
                             static_cast<double>(in.ConsumeIntegral<std::int32_t>()),
                             in.ConsumeFloatingPointInRange<double>(-1e6, 1e6),
                             in.ConsumeFloatingPointInRange<double>(-1e6, 1e6)};
  }
  for (int n = in.ConsumeIntegralInRange<int>(0, 2); n > 0; --n) c.open_circuit_codes.push_back(in.ConsumeIntegral<std::int32_t>());
  for (int n = in.ConsumeIntegralInRange<int>(0, 2); n > 0; --n) c.out_of_range_codes.push_back(in.ConsumeIntegral<std::int32_t>());
  c.valid_min = maybe_number(in);
  c.valid_max = maybe_number(in);
  return c;
}

void check_reading(const ModbusChannel& c, const ChannelReading& r) {
  const int status = static_cast<int>(r.status);
  FUZZ_CHECK(status >= 0 && status < bosfuse::storage::kSampleStatusCount);
  FUZZ_CHECK(r.value.has_value() == (r.status == SampleStatus::kOk));
  if (!std::isfinite(r.raw)) FUZZ_CHECK(r.status != SampleStatus::kOk);
  for (double code : c.open_circuit_codes) FUZZ_CHECK(!(r.raw == code && r.status == SampleStatus::kOk));
  for (double code : c.out_of_range_codes) FUZZ_CHECK(!(r.raw == code && r.status == SampleStatus::kOk));
  if (r.value) {
    FUZZ_CHECK(std::isfinite(*r.value));
    if (c.valid_min) FUZZ_CHECK(*r.value >= *c.valid_min);
    if (c.valid_max) FUZZ_CHECK(*r.value <= *c.valid_max);
  }
}

void check_round_trip(std::span<const std::uint16_t> words, DataType type, WordOrder order) {
  const double value = decode_registers(words, type, order);
  if (type == DataType::kFloat32 && std::isnan(value)) return;  // NaN payloads need not survive
  const std::vector<std::uint16_t> again = encode_registers(value, type, order);
  FUZZ_CHECK(again.size() == static_cast<std::size_t>(register_count(type)));
  for (std::size_t i = 0; i < again.size(); ++i) FUZZ_CHECK(again[i] == words[i]);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  std::vector<ModbusChannel> channels;
  const int wanted = in.ConsumeIntegralInRange<int>(1, 16);
  for (int i = 0; i < wanted; ++i) {
    ModbusChannel c = make_channel(in, i);
    if (!c.Validate().empty()) continue;
    channels.push_back(std::move(c));
  }

  // The device's answer: whatever words are left (repeated to fill every block).
  std::vector<std::uint16_t> words;
  while (in.remaining_bytes() >= 2) words.push_back(in.ConsumeIntegral<std::uint16_t>());
  if (words.empty()) words.push_back(0);

  for (int type = 0; type <= 4; ++type) {
    for (int order = 0; order <= 3; ++order) {
      if (words.size() >= 2) check_round_trip(words, static_cast<DataType>(type), static_cast<WordOrder>(order));
    }
  }

  const std::vector<RegisterBlock> blocks = plan_register_blocks(channels);
  std::vector<std::vector<std::uint16_t>> replies;
  std::size_t next = 0;
  for (const RegisterBlock& block : blocks) {
    FUZZ_CHECK(block.count >= 1 && block.count <= 125);
    FUZZ_CHECK(block.address >= 0 && block.address + block.count <= 0x10000);
    std::vector<std::uint16_t> reply(static_cast<std::size_t>(block.count));
    for (auto& w : reply) w = words[next++ % words.size()];
    replies.push_back(std::move(reply));
  }
  for (const ModbusChannel& c : channels) {
    bool covered = false;
    for (std::size_t b = 0; b < blocks.size() && !covered; ++b) {
      const int offset = c.address - blocks[b].address;
      if (c.function != blocks[b].function || offset < 0 || offset + c.register_count() > blocks[b].count) continue;
      covered = true;
      check_reading(c, c.decode(std::span(replies[b]).subspan(static_cast<std::size_t>(offset))));
    }
    FUZZ_CHECK(covered);
  }
  return 0;
}
