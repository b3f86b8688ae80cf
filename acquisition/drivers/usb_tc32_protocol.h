#pragma once
// The vendor requests of the Measurement Computing USB-TC-32 (09db:0131), a
// 32-channel thermocouple logger that is not a HID device: each reading is a
// vendor control transfer (device-to-host, bmRequestType 0xC0) returning a
// float32, little-endian. TIN (0x10) reads a thermocouple with wValue = the
// channel and wIndex = (wait << 8) | units; CJC (0x11) reads the cold-
// junction sensor of a channel; TIN_CONFIG (0x14, host-to-device, 64 bytes)
// sets each channel's thermocouple type (0 disables it). The device reports
// problems as values: -777 a common-mode voltage error, -888 an open
// thermocouple, -999 a disabled channel (as in Measurement Computing's
// documentation and open-source Linux driver). Kept apart from libusb so it
// can be tested byte for byte.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "acquisition/device_reading.h"

namespace bosfuse::acquisition {

inline constexpr std::uint16_t kUsbTc32VendorId = 0x09db;
inline constexpr std::uint16_t kUsbTc32ProductId = 0x0131;
inline constexpr int kUsbTc32Inputs = 32;  // one base unit; 64 with the expansion board

struct ControlRequest {
  std::uint8_t request_type = 0;   // bmRequestType
  std::uint8_t request = 0;        // bRequest
  std::uint16_t value = 0;         // wValue
  std::uint16_t index = 0;         // wIndex
  std::vector<std::uint8_t> data;  // sent (host-to-device) or sized for the reply
  bool operator==(const ControlRequest&) const = default;
};

// The 8-byte setup packet of a request, as it goes on the wire.
std::array<std::uint8_t, 8> setup_packet(const ControlRequest& request);

// Reads thermocouple `input` in degC, the latest conversion (no waiting).
ControlRequest tc32_temperature_request(int input);
// Reads the cold-junction sensor that serves `input`, in degC.
ControlRequest tc32_cold_junction_request(int input);
// Sets the thermocouple type of every input; inputs not listed are disabled.
ControlRequest tc32_type_config_request(std::span<const std::pair<int, char>> input_types);
// Device code of a thermocouple type (J 1 K 2 T 3 E 4 R 5 S 6 B 7 N 8).
std::optional<std::uint8_t> tc32_type_code(char tc_type);

// A reply to a temperature or cold-junction request, sentinels turned into
// statuses; a reply that is not 4 bytes is bad-reply.
ChannelReading decode_tc32_reading(std::span<const std::uint8_t> reply);

}  // namespace bosfuse::acquisition
