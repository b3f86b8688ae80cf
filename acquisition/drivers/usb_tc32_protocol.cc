#include "acquisition/drivers/usb_tc32_protocol.h"

#include <cmath>
#include <string_view>

#include "acquisition/drivers/hid_protocol.h"  // decode_hid_value: the same little-endian float32

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

constexpr std::uint8_t kDeviceToHostVendor = 0xC0;
constexpr std::uint8_t kHostToDeviceVendor = 0x40;
constexpr std::uint8_t kTin = 0x10;
constexpr std::uint8_t kCjc = 0x11;
constexpr std::uint8_t kTinConfig = 0x14;
constexpr std::uint8_t kUnitsCelsius = 0;
constexpr std::uint8_t kNoWait = 0;
constexpr std::size_t kConfigBytes = 64;

constexpr double kCommonModeError = -777.0;
constexpr double kOpenThermocouple = -888.0;
constexpr double kDisabledChannel = -999.0;

ControlRequest read_float(std::uint8_t request, int input) {
  return {kDeviceToHostVendor, request, static_cast<std::uint16_t>(input),
          static_cast<std::uint16_t>(kNoWait << 8 | kUnitsCelsius), std::vector<std::uint8_t>(4)};
}

}  // namespace

std::array<std::uint8_t, 8> setup_packet(const ControlRequest& r) {
  const auto length = static_cast<std::uint16_t>(r.data.size());
  return {r.request_type,
          r.request,
          static_cast<std::uint8_t>(r.value),
          static_cast<std::uint8_t>(r.value >> 8),
          static_cast<std::uint8_t>(r.index),
          static_cast<std::uint8_t>(r.index >> 8),
          static_cast<std::uint8_t>(length),
          static_cast<std::uint8_t>(length >> 8)};
}

ControlRequest tc32_temperature_request(int input) { return read_float(kTin, input); }

ControlRequest tc32_cold_junction_request(int input) { return read_float(kCjc, input); }

// The USB-TC's type order, shifted by one: 0 means disabled here.
std::optional<std::uint8_t> tc32_type_code(char tc_type) {
  const auto code = mcc_tc_type_code(std::string_view(&tc_type, 1));
  if (!code) return std::nullopt;
  return static_cast<std::uint8_t>(*code + 1);
}

ControlRequest tc32_type_config_request(std::span<const std::pair<int, char>> input_types) {
  ControlRequest request{kHostToDeviceVendor, kTinConfig, 0, 0, std::vector<std::uint8_t>(kConfigBytes, 0)};
  for (const auto& [input, type] : input_types) {
    if (input >= 0 && static_cast<std::size_t>(input) < kConfigBytes)
      request.data[input] = tc32_type_code(type).value_or(0);
  }
  return request;
}

ChannelReading decode_tc32_reading(std::span<const std::uint8_t> reply) {
  if (reply.size() != 4) return {std::nullopt, std::nan(""), SampleStatus::kBadReply};
  const double value = *decode_hid_value(reply, 0, HidValueType::kFloat32, /*big_endian=*/false);
  if (!std::isfinite(value)) return {std::nullopt, value, SampleStatus::kInvalidValue};
  if (value == kOpenThermocouple) return {std::nullopt, value, SampleStatus::kOpenCircuit};
  if (value == kCommonModeError) return {std::nullopt, value, SampleStatus::kOutOfRange};
  if (value == kDisabledChannel) return {std::nullopt, value, SampleStatus::kDisabled};
  return {value, value, SampleStatus::kOk};
}

}  // namespace bosfuse::acquisition
