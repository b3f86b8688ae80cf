#include "acquisition/drivers/hid_protocol.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

constexpr std::uint8_t kMccTin = 0x18;
constexpr std::uint8_t kMccSetItem = 0x49;
constexpr std::uint8_t kMccGetBurnoutStatus = 0x4C;
constexpr std::uint8_t kMccSubItemChannel0Tc = 0x10;
constexpr std::uint8_t kMccUnitsCelsius = 0;
// What Measurement Computing's software reports for an open input.
constexpr double kMccOpenInputCode = -9999.0;

constexpr std::array<std::string_view, 5> kHidValueTypeNames = {"int16", "uint16", "int32", "uint32", "float32"};

int byte_count(HidValueType type) { return type == HidValueType::kInt16 || type == HidValueType::kUint16 ? 2 : 4; }

std::uint32_t assemble(std::span<const std::uint8_t> bytes, bool big_endian) {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const std::size_t shift = 8 * (big_endian ? bytes.size() - 1 - i : i);
    value |= static_cast<std::uint32_t>(bytes[i]) << shift;
  }
  return value;
}

}  // namespace

std::optional<HidValueType> parse_hid_value_type(std::string_view text) {
  for (std::size_t i = 0; i < kHidValueTypeNames.size(); ++i) {
    if (kHidValueTypeNames[i] == text) return static_cast<HidValueType>(i);
  }
  return std::nullopt;
}

std::optional<double> decode_hid_value(std::span<const std::uint8_t> bytes, int offset, HidValueType type,
                                       bool big_endian) {
  const int size = byte_count(type);
  if (offset < 0 || static_cast<std::size_t>(offset + size) > bytes.size()) return std::nullopt;
  const std::uint32_t bits =
      assemble(bytes.subspan(static_cast<std::size_t>(offset), static_cast<std::size_t>(size)), big_endian);
  switch (type) {
    case HidValueType::kInt16:
      return static_cast<std::int16_t>(bits);
    case HidValueType::kUint16:
      return static_cast<std::uint16_t>(bits);
    case HidValueType::kInt32:
      return static_cast<std::int32_t>(bits);
    case HidValueType::kUint32:
      return bits;
    case HidValueType::kFloat32:
      return std::bit_cast<float>(bits);
  }
  return std::nullopt;
}

std::string HidChannel::Validate() const {
  if (name.empty()) return "channel has no name";
  if (request.empty()) return "channel has no request bytes";
  if (value_offset < 0 || value_offset > 63) return "value offset must be within a 64-byte report";
  if (!std::isfinite(scale) || scale == 0) return "scale must be a finite non-zero number";
  if (valid_min && valid_max && *valid_min >= *valid_max) return "valid range is empty";
  return {};
}

std::size_t HidChannel::reply_size() const { return static_cast<std::size_t>(value_offset + byte_count(type)); }

std::optional<double> HidChannel::stored_resolution() const {
  if (resolution) return resolution;
  if (type == HidValueType::kFloat32 || !(scale != 0) || !std::isfinite(scale)) return std::nullopt;
  return std::abs(scale);
}

ChannelReading HidChannel::decode(std::span<const std::uint8_t> reply) const {
  ChannelReading reading;
  const bool wrong_report = reply_report_id && (reply.empty() || reply[0] != *reply_report_id);
  const auto raw = wrong_report ? std::nullopt : decode_hid_value(reply, value_offset, type, big_endian);
  if (!raw) {
    reading.status = SampleStatus::kBadReply;
    reading.raw = std::nan("");
    return reading;
  }
  reading.raw = *raw;
  if (!std::isfinite(*raw)) {
    reading.status = SampleStatus::kInvalidValue;
  } else if (is_one_of_codes(open_circuit_codes, *raw)) {
    reading.status = SampleStatus::kOpenCircuit;
  } else {
    const double value = *raw * scale + offset;
    const bool outside = (valid_min && value < *valid_min) || (valid_max && value > *valid_max);
    reading.status = outside ? SampleStatus::kOutOfRange : SampleStatus::kOk;
    if (!outside) reading.value = value;
  }
  return reading;
}

void HidProtocol::apply_burnout(std::span<const std::uint8_t> reply, std::vector<ChannelReading>& readings) const {
  const bool valid = reply.size() >= 2 && (!burnout_reply_report_id || reply[0] == *burnout_reply_report_id);
  for (std::size_t i = 0; i < channels.size() && i < readings.size(); ++i) {
    const int bit = channels[i].burnout_bit;
    if (bit < 0) continue;
    if (!valid) {
      readings[i] = {std::nullopt, readings[i].raw, SampleStatus::kBadReply};
    } else if (reply[1] & (1u << bit)) {
      readings[i] = {std::nullopt, readings[i].raw, SampleStatus::kOpenCircuit};
    }
  }
}

std::optional<std::uint8_t> mcc_tc_type_code(std::string_view tc_type) {
  static constexpr std::string_view kOrder = "JKTERSBN";
  if (tc_type.size() != 1) return std::nullopt;
  const auto at = kOrder.find(static_cast<char>(std::toupper(static_cast<unsigned char>(tc_type[0]))));
  if (at == std::string_view::npos) return std::nullopt;
  return static_cast<std::uint8_t>(at);
}

HidChannel mcc_usb_tc_channel(int input) {
  HidChannel channel;
  channel.request = {kMccTin, static_cast<std::uint8_t>(input), kMccUnitsCelsius};
  channel.reply_report_id = kMccTin;
  channel.value_offset = 1;
  channel.type = HidValueType::kFloat32;
  channel.open_circuit_codes = {kMccOpenInputCode};
  if (input >= kMccColdJunction0) {
    channel.kind = "cold-junction";
  } else {
    channel.burnout_bit = input;
  }
  return channel;
}

std::vector<std::uint8_t> mcc_set_tc_type_request(int input, std::uint8_t type_code) {
  return {kMccSetItem, static_cast<std::uint8_t>(input / 2),
          static_cast<std::uint8_t>(kMccSubItemChannel0Tc + input % 2), type_code};
}

// Mask 0: every burnout bit is cleared after it is read, so each poll sees
// the inputs open since the previous one.
std::vector<std::uint8_t> mcc_burnout_request() { return {kMccGetBurnoutStatus, 0x00}; }

HidChannel temper_channel(double divisor) {
  HidChannel channel;
  channel.request = {0x00, 0x01, 0x80, 0x33, 0x01, 0x00, 0x00, 0x00, 0x00};
  channel.value_offset = 2;
  channel.type = HidValueType::kInt16;
  channel.big_endian = true;
  channel.scale = 1.0 / divisor;
  channel.kind = "temperature";
  return channel;
}

}  // namespace bosfuse::acquisition
