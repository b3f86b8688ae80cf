#pragma once
// The bytes USB-HID thermometers exchange, kept apart from hidapi so every
// request and reply can be tested byte for byte. A HidChannel says which
// report to send to read one channel and where the value sits in the reply;
// built-in profiles fill it in:
//   mcc-usb-tc  Measurement Computing USB-TC (09db:0090): request
//               [0x18 TIN, channel, units 0 = degC] -> [0x18, float32 LE];
//               cold junctions are channels 0x80 and 0x81; burnout query
//               [0x4C, mask] -> [0x4C, bitmap of open inputs]; thermocouple
//               type set with SET_ITEM [0x49, channel/2, 0x10 + channel%2,
//               type code J0 K1 T2 E3 R4 S5 B6 N7] (as in the open-source
//               Linux driver for the device).
//   temper      TEMPer USB thermometers (0c45:7401 and relatives, interface
//               1): request 01 80 33 01 00 00 00 00 (report id 0), reply of
//               8 bytes with the temperature as big-endian int16 at bytes
//               2-3, divided by a firmware-dependent factor (256 or 100).
//   generic-hid everything from the configuration.
// The first byte of every request is the HID report id (0 for devices that
// use none), as hidapi expects.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/alarm_limits.h"
#include "acquisition/device_reading.h"

namespace bosfuse::acquisition {

enum class HidValueType { kInt16, kUint16, kInt32, kUint32, kFloat32 };

struct HidChannel {
  // What it measures.
  std::string name;
  std::string kind = "thermocouple";
  std::string unit = "degC";
  std::optional<std::string> tc_type;
  std::optional<double> image_x_px;
  std::optional<double> image_y_px;
  std::optional<double> time_constant_s;  // the sensor's first-order response time (agreement removes its lag)
  std::optional<double> resolution;       // the experiment file's `resolution`, in `unit`

  // How it is read.
  std::vector<std::uint8_t> request;            // report id first
  std::optional<std::uint8_t> reply_report_id;  // checked when set
  int value_offset = 1;                         // byte offset in the reply
  HidValueType type = HidValueType::kFloat32;
  bool big_endian = false;
  double scale = 1.0;  // value = raw * scale + offset
  double offset = 0.0;
  std::vector<double> open_circuit_codes;
  std::optional<double> valid_min;
  std::optional<double> valid_max;
  int burnout_bit = -1;  // bit of the device's burnout bitmap, if it has one
  AlarmLimits alarms{};

  std::string Validate() const;
  std::size_t reply_size() const;  // bytes the reply must have at least
  ChannelReading decode(std::span<const std::uint8_t> reply) const;
  // The file's resolution, else the step of one count of an integer value
  // (|scale|); none for a float value.
  std::optional<double> stored_resolution() const;
};

// A device's whole conversation: the reports sent once after opening (type
// set-up), the channels, and an optional burnout query.
struct HidProtocol {
  std::vector<std::vector<std::uint8_t>> setup_requests;
  std::vector<HidChannel> channels;
  std::optional<std::vector<std::uint8_t>> burnout_request;
  std::optional<std::uint8_t> burnout_reply_report_id;

  // Marks channels whose burnout bit is set in `reply` as open-circuit.
  // A malformed reply marks every channel with a burnout bit bad-reply.
  void apply_burnout(std::span<const std::uint8_t> reply, std::vector<ChannelReading>& readings) const;
};

std::optional<HidValueType> parse_hid_value_type(std::string_view text);

// Decodes a number of `type` at `offset`; nullopt when the reply is short.
std::optional<double> decode_hid_value(std::span<const std::uint8_t> bytes, int offset, HidValueType type,
                                       bool big_endian);

// MCC USB-TC.
inline constexpr std::uint16_t kMccVendorId = 0x09db;
inline constexpr std::uint16_t kMccUsbTcProductId = 0x0090;
inline constexpr std::uint8_t kMccColdJunction0 = 0x80;
std::optional<std::uint8_t> mcc_tc_type_code(std::string_view tc_type);
// input 0-7 for thermocouples, kMccColdJunction0 / +1 for the cold junctions.
HidChannel mcc_usb_tc_channel(int input);
std::vector<std::uint8_t> mcc_set_tc_type_request(int input, std::uint8_t type_code);
std::vector<std::uint8_t> mcc_burnout_request();

// TEMPer.
inline constexpr std::uint16_t kTemperVendorId = 0x0c45;
inline constexpr std::uint16_t kTemperProductId = 0x7401;
inline constexpr int kTemperInterface = 1;
HidChannel temper_channel(double divisor);

}  // namespace bosfuse::acquisition
