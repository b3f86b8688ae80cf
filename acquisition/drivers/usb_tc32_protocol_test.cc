// USB-TC-32 requests byte for byte, and its replies decoded from recorded
// bytes (umockdev cannot replay vendor control transfers to libusb, so the
// transfer itself is not emulated; see tests/umockdev_usb_test.cc for what is).

#include "acquisition/drivers/usb_tc32_protocol.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;
using Bytes = std::vector<std::uint8_t>;

Bytes packet(const ControlRequest& r) {
  const auto p = setup_packet(r);
  return {p.begin(), p.end()};
}

TEST(UsbTc32Protocol, TemperatureRequestIsAVendorReadOfFourBytes) {
  // bmRequestType C0, TIN 0x10, wValue = channel 37, wIndex = no wait | degC, wLength 4.
  EXPECT_EQ(packet(tc32_temperature_request(37)), (Bytes{0xC0, 0x10, 37, 0, 0, 0, 4, 0}));
  EXPECT_EQ(packet(tc32_cold_junction_request(2)), (Bytes{0xC0, 0x11, 2, 0, 0, 0, 4, 0}));
}

TEST(UsbTc32Protocol, TypeConfigurationDisablesInputsNotListed) {
  const std::vector<std::pair<int, char>> types = {{0, 'K'}, {1, 'j'}, {31, 'N'}};
  const ControlRequest r = tc32_type_config_request(types);
  EXPECT_EQ(packet(r), (Bytes{0x40, 0x14, 0, 0, 0, 0, 64, 0}));
  ASSERT_EQ(r.data.size(), 64u);
  EXPECT_EQ(r.data[0], 2);   // K
  EXPECT_EQ(r.data[1], 1);   // J
  EXPECT_EQ(r.data[2], 0);   // disabled
  EXPECT_EQ(r.data[31], 8);  // N
  EXPECT_FALSE(tc32_type_code('C').has_value());
}

// Replies as the device sends them: float32, little-endian.
TEST(UsbTc32Protocol, RecordedRepliesDecodeToTemperaturesAndStatuses) {
  const auto ok = decode_tc32_reading(Bytes{0x00, 0x00, 0xBC, 0x41});  // 23.5
  EXPECT_EQ(ok.status, SampleStatus::kOk);
  EXPECT_DOUBLE_EQ(ok.value.value_or(NAN), 23.5);
  const auto open = decode_tc32_reading(Bytes{0x00, 0x00, 0x5E, 0xC4});  // -888
  EXPECT_EQ(open.status, SampleStatus::kOpenCircuit);
  EXPECT_FALSE(open.value.has_value());
  EXPECT_DOUBLE_EQ(open.raw, -888.0);
  EXPECT_EQ(decode_tc32_reading(Bytes{0x00, 0x40, 0x42, 0xC4}).status, SampleStatus::kOutOfRange);    // -777
  EXPECT_EQ(decode_tc32_reading(Bytes{0x00, 0xC0, 0x79, 0xC4}).status, SampleStatus::kDisabled);      // -999
  EXPECT_EQ(decode_tc32_reading(Bytes{0x00, 0x00, 0xC0, 0x7F}).status, SampleStatus::kInvalidValue);  // NaN
  EXPECT_EQ(decode_tc32_reading(Bytes{0x00, 0x00, 0xBC}).status, SampleStatus::kBadReply);
  EXPECT_EQ(decode_tc32_reading(Bytes{0x00, 0x00, 0xBC, 0x41, 0x00}).status, SampleStatus::kBadReply);
}

}  // namespace
}  // namespace bosfuse::acquisition
