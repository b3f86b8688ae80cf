// HID report decoding byte for byte; the hidapi path itself is tested under
// umockdev in tests/umockdev_hid_test.cc.

#include "acquisition/drivers/hid_protocol.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;
using Bytes = std::vector<std::uint8_t>;

TEST(HidProtocol, EveryTypeAndByteOrderDecodes) {
  const Bytes reply = {0x07, 0xFF, 0x38, 0x12, 0x34};
  EXPECT_EQ(decode_hid_value(reply, 1, HidValueType::kInt16, false), std::int16_t(0x38FF));
  EXPECT_EQ(decode_hid_value(reply, 1, HidValueType::kInt16, true), std::int16_t(0xFF38));
  EXPECT_EQ(decode_hid_value(reply, 1, HidValueType::kUint16, true), 0xFF38);
  EXPECT_EQ(decode_hid_value(reply, 1, HidValueType::kInt32, true), std::int32_t(0xFF381234));
  EXPECT_EQ(decode_hid_value(reply, 1, HidValueType::kUint32, false), 0x341238FFu);
  EXPECT_EQ(decode_hid_value(Bytes{0x00, 0x00, 0xBC, 0x41}, 0, HidValueType::kFloat32, false), 23.5);
  EXPECT_FALSE(decode_hid_value(reply, 2, HidValueType::kInt32, false).has_value());  // one byte short
}

TEST(HidProtocol, ChannelChecksReportIdScalesAndFlags) {
  HidChannel c;
  c.name = "t";
  c.request = {0x01};
  c.reply_report_id = 0x07;
  c.value_offset = 1;
  c.type = HidValueType::kInt16;
  c.big_endian = true;
  c.scale = 0.01;
  c.open_circuit_codes = {32767};
  c.valid_max = 300.0;
  EXPECT_DOUBLE_EQ(c.decode(Bytes{0x07, 0x09, 0xC4}).value.value_or(NAN), 25.0);
  EXPECT_EQ(c.decode(Bytes{0x08, 0x09, 0xC4}).status, SampleStatus::kBadReply);  // another report
  EXPECT_EQ(c.decode(Bytes{0x07, 0x7F, 0xFF}).status, SampleStatus::kOpenCircuit);
  EXPECT_EQ(c.decode(Bytes{0x07, 0x75, 0x31}).status, SampleStatus::kOutOfRange);  // 300.01 > valid_max
}

TEST(HidProtocol, MccTypeCodesAndSetItemReport) {
  EXPECT_EQ(mcc_tc_type_code("J"), 0);
  EXPECT_EQ(mcc_tc_type_code("n"), 7);
  EXPECT_FALSE(mcc_tc_type_code("X").has_value());
  EXPECT_EQ(mcc_set_tc_type_request(5, 1), (Bytes{0x49, 2, 0x11, 1}));
}

}  // namespace
}  // namespace bosfuse::acquisition
