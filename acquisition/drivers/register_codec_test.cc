#include "acquisition/drivers/register_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tuple>

namespace bosfuse::acquisition {
namespace {

using Registers = std::vector<std::uint16_t>;

struct WireCase {
  DataType type;
  WordOrder order;
  Registers registers;  // as libmodbus delivers them
  double value;
};

// Bytes A B C D of 0x12345678 in each order, and the 16-bit analogues.
const WireCase kCases[] = {
    {DataType::kUint32, WordOrder::kABCD, {0x1234, 0x5678}, 0x12345678},
    {DataType::kUint32, WordOrder::kCDAB, {0x5678, 0x1234}, 0x12345678},
    {DataType::kUint32, WordOrder::kBADC, {0x3412, 0x7856}, 0x12345678},
    {DataType::kUint32, WordOrder::kDCBA, {0x7856, 0x3412}, 0x12345678},
    {DataType::kInt32, WordOrder::kABCD, {0xFFFF, 0xFFFE}, -2},
    {DataType::kInt32, WordOrder::kCDAB, {0xFFFE, 0xFFFF}, -2},
    {DataType::kInt32, WordOrder::kBADC, {0xFFFF, 0xFEFF}, -2},
    {DataType::kInt32, WordOrder::kDCBA, {0xFEFF, 0xFFFF}, -2},
    {DataType::kInt32, WordOrder::kABCD, {0x8000, 0x0000}, -2147483648.0},
    {DataType::kFloat32, WordOrder::kABCD, {0x41C8, 0x0000}, 25.0},  // 25.0f = 0x41C80000
    {DataType::kFloat32, WordOrder::kCDAB, {0x0000, 0x41C8}, 25.0},
    {DataType::kFloat32, WordOrder::kBADC, {0xC841, 0x0000}, 25.0},
    {DataType::kFloat32, WordOrder::kDCBA, {0x0000, 0xC841}, 25.0},
    {DataType::kFloat32, WordOrder::kABCD, {0xC2F6, 0xE979}, -123.456001281738},  // -123.456f
    {DataType::kUint16, WordOrder::kABCD, {0x1234}, 0x1234},
    {DataType::kUint16, WordOrder::kCDAB, {0x1234}, 0x1234},
    {DataType::kUint16, WordOrder::kBADC, {0x3412}, 0x1234},
    {DataType::kUint16, WordOrder::kDCBA, {0x3412}, 0x1234},
    {DataType::kUint16, WordOrder::kABCD, {0xFFFF}, 65535},
    {DataType::kInt16, WordOrder::kABCD, {0xFFFE}, -2},
    {DataType::kInt16, WordOrder::kCDAB, {0xFFFE}, -2},
    {DataType::kInt16, WordOrder::kBADC, {0xFEFF}, -2},
    {DataType::kInt16, WordOrder::kDCBA, {0xFEFF}, -2},
    {DataType::kInt16, WordOrder::kABCD, {0x8000}, -32768},
};

class WireFormat : public ::testing::TestWithParam<WireCase> {};

TEST_P(WireFormat, DecodesTheDocumentedBytes) {
  const WireCase& c = GetParam();
  EXPECT_NEAR(decode_registers(c.registers, c.type, c.order), c.value, 1e-9);
}

TEST_P(WireFormat, EncodesTheSameBytes) {
  const WireCase& c = GetParam();
  EXPECT_EQ(encode_registers(c.value, c.type, c.order), c.registers);
}

INSTANTIATE_TEST_SUITE_P(AllTypesAndOrders, WireFormat, ::testing::ValuesIn(kCases));

TEST(RegisterCodec, EncodeSaturatesAndRounds) {
  EXPECT_EQ(encode_registers(70000, DataType::kUint16, WordOrder::kABCD), Registers{0xFFFF});
  EXPECT_EQ(encode_registers(-5, DataType::kUint16, WordOrder::kABCD), Registers{0x0000});
  EXPECT_EQ(encode_registers(-40000, DataType::kInt16, WordOrder::kABCD), Registers{0x8000});
  EXPECT_EQ(encode_registers(2.6, DataType::kInt16, WordOrder::kABCD), Registers{0x0003});
  EXPECT_EQ(encode_registers(1e12, DataType::kUint32, WordOrder::kABCD), (Registers{0xFFFF, 0xFFFF}));
}

TEST(RegisterCodec, FloatNanSurvivesDecoding) {
  const Registers nan_bits = {0x7FC0, 0x0000};
  EXPECT_TRUE(std::isnan(decode_registers(nan_bits, DataType::kFloat32, WordOrder::kABCD)));
}

TEST(RegisterCodec, TooFewRegistersIsAnError) {
  const Registers one = {0x1234};
  EXPECT_THROW(decode_registers(one, DataType::kFloat32, WordOrder::kABCD), std::invalid_argument);
}

TEST(RegisterCodec, NamesParseBothWays) {
  for (auto type : {DataType::kInt16, DataType::kUint16, DataType::kInt32, DataType::kUint32, DataType::kFloat32}) {
    EXPECT_EQ(parse_data_type(to_string(type)), type);
  }
  for (auto order : {WordOrder::kABCD, WordOrder::kCDAB, WordOrder::kBADC, WordOrder::kDCBA}) {
    EXPECT_EQ(parse_word_order(to_string(order)), order);
  }
  EXPECT_EQ(parse_word_order("cdab"), WordOrder::kCDAB);
  EXPECT_FALSE(parse_data_type("double").has_value());
}

}  // namespace
}  // namespace bosfuse::acquisition
