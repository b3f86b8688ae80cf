#include "acquisition/drivers/modbus_channel.h"

#include <algorithm>
#include <cmath>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

}  // namespace

std::string ModbusChannel::Validate() const {
  if (name.empty()) return "channel has no name";
  if (address < 0 || address > 0xFFFF) return "address " + std::to_string(address) + " is not in 0..65535";
  if (address + register_count() > 0x10000) {
    return "a " + std::to_string(register_count()) + "-register value at address " + std::to_string(address) +
           " runs past the last register (65535)";
  }
  if (!std::isfinite(scale) || scale == 0) return "scale must be a finite non-zero number";
  if (!std::isfinite(offset)) return "offset must be finite";
  if (linear && (linear->raw_high == linear->raw_low || linear->value_high == linear->value_low)) {
    return "linear mapping needs distinct raw and value end points";
  }
  if (valid_min && valid_max && *valid_min >= *valid_max) return "valid range is empty";
  return {};
}

double ModbusChannel::to_value(double raw) const {
  if (linear) {
    return linear->value_low +
           (raw - linear->raw_low) * (linear->value_high - linear->value_low) / (linear->raw_high - linear->raw_low);
  }
  return raw * scale + offset;
}

std::optional<double> ModbusChannel::register_step() const {
  if (type == DataType::kFloat32) return std::nullopt;
  const double step = linear ? std::abs((linear->value_high - linear->value_low) / (linear->raw_high - linear->raw_low))
                             : std::abs(scale);
  if (!(step > 0) || !std::isfinite(step)) return std::nullopt;
  return step;
}

double ModbusChannel::to_raw(double value) const {
  if (linear) {
    return linear->raw_low + (value - linear->value_low) * (linear->raw_high - linear->raw_low) /
                                 (linear->value_high - linear->value_low);
  }
  return (value - offset) / scale;
}

ChannelReading ModbusChannel::decode(std::span<const std::uint16_t> registers) const {
  ChannelReading reading;
  reading.raw = decode_registers(registers, type, order);
  if (!std::isfinite(reading.raw)) {
    reading.status = SampleStatus::kInvalidValue;
  } else if (is_one_of_codes(open_circuit_codes, reading.raw)) {
    reading.status = SampleStatus::kOpenCircuit;
  } else if (is_one_of_codes(out_of_range_codes, reading.raw)) {
    reading.status = SampleStatus::kOutOfRange;
  } else {
    const double value = to_value(reading.raw);
    const bool below = valid_min && value < *valid_min;
    const bool above = valid_max && value > *valid_max;
    reading.status = (below || above) ? SampleStatus::kOutOfRange : SampleStatus::kOk;
    if (reading.status == SampleStatus::kOk) reading.value = value;
  }
  return reading;
}

std::vector<std::uint16_t> ModbusChannel::encode(double value) const { return encode_raw(to_raw(value)); }

std::vector<std::uint16_t> ModbusChannel::encode_raw(double raw) const { return encode_registers(raw, type, order); }

}  // namespace bosfuse::acquisition
