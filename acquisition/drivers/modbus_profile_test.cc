#include "acquisition/drivers/modbus_profile.h"

#include <gtest/gtest.h>

#include "acquisition/drivers/modbus_device.h"

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;
using Registers = std::vector<std::uint16_t>;

TEST(Adam6018, MapsUint16LinearlyOverTheTypeRange) {
  const ModbusChannel k = profile_input_channel("adam-6018", 3, "K");
  EXPECT_EQ(k.function, RegisterKind::kHolding);
  EXPECT_EQ(k.address, 3);
  EXPECT_DOUBLE_EQ(*k.decode(Registers{0}).value, 0.0);
  EXPECT_DOUBLE_EQ(*k.decode(Registers{65534}).value, 1370.0 * 65534 / 65535);
  EXPECT_NEAR(*k.decode(Registers{32768}).value, 685.01, 0.01);
  const ModbusChannel t = profile_input_channel("adam-6018", 0, "T");
  EXPECT_DOUBLE_EQ(*t.decode(Registers{0}).value, -100.0);
}

TEST(Adam6018, BurnoutCodeIsOpenCircuitNotATemperature) {
  const ChannelReading r = profile_input_channel("adam-6018", 0, "K").decode(Registers{0xFFFF});
  EXPECT_EQ(r.status, SampleStatus::kOpenCircuit);
  EXPECT_FALSE(r.value.has_value());
  EXPECT_EQ(r.raw, 65535);
}

TEST(Adam6018, RejectsUnknownTypeAndInput) {
  EXPECT_THROW(profile_input_channel("adam-6018", 0, "X"), std::invalid_argument);
  EXPECT_THROW(profile_input_channel("adam-6018", 8, "K"), std::invalid_argument);
  EXPECT_THROW(profile_cold_junction_channel("adam-6018"), std::invalid_argument);
}

TEST(IcpdasM7018, EngineeringUnitsInHundredthsOfADegree) {
  const ModbusChannel c = profile_input_channel("icpdas-m7018", 2, "K");
  EXPECT_EQ(c.function, RegisterKind::kInput);
  EXPECT_EQ(c.address, 2);
  EXPECT_DOUBLE_EQ(*c.decode(Registers{2534}).value, 25.34);
  EXPECT_DOUBLE_EQ(*c.decode(Registers{static_cast<std::uint16_t>(-1234)}).value, -12.34);
  EXPECT_EQ(c.decode(Registers{0x7FFF}).status, SampleStatus::kOpenCircuit);
  EXPECT_EQ(c.decode(Registers{0x8000}).status, SampleStatus::kOutOfRange);
}

TEST(IcpdasM7018, ColdJunctionIsItsOwnChannel) {
  const ModbusChannel cj = profile_cold_junction_channel("icpdas-m7018");
  EXPECT_EQ(cj.kind, "cold-junction");
  EXPECT_EQ(cj.function, RegisterKind::kInput);
  EXPECT_EQ(cj.address, 128);
  EXPECT_DOUBLE_EQ(*cj.decode(Registers{2250}).value, 22.5);
}

TEST(Generic, HasNoBuiltInInputs) {
  EXPECT_THROW(profile_input_channel("generic", 0, "K"), std::invalid_argument);
  EXPECT_EQ(find_modbus_profile("nonesuch"), nullptr);
}

TEST(ModbusChannel, ValidRangeMarksOutOfRange) {
  ModbusChannel c;
  c.name = "oven";
  c.type = DataType::kFloat32;
  c.valid_min = -50;
  c.valid_max = 1000;
  EXPECT_EQ(c.decode(c.encode(1200)).status, SampleStatus::kOutOfRange);
  EXPECT_EQ(c.decode(c.encode(999)).status, SampleStatus::kOk);
  EXPECT_EQ(c.decode(c.encode_raw(std::numeric_limits<double>::quiet_NaN())).status, SampleStatus::kInvalidValue);
}

// Found by fuzzing: a 32-bit value at address 65535 was accepted, though
// its second register does not exist.
TEST(ModbusChannel, AValueRunningPastTheLastRegisterIsRefused) {
  ModbusChannel c;
  c.name = "oven";
  c.type = DataType::kFloat32;
  c.address = 65534;
  EXPECT_EQ(c.Validate(), "");
  c.address = 65535;
  EXPECT_EQ(c.Validate(), "a 2-register value at address 65535 runs past the last register (65535)");
  c.type = DataType::kUint16;
  EXPECT_EQ(c.Validate(), "");
}

TEST(ModbusChannel, EncodeIsTheInverseOfDecode) {
  for (const char* profile : {"adam-6018", "icpdas-m7018"}) {
    const ModbusChannel c = profile_input_channel(profile, 1, "K");
    for (double t : {0.5, 22.0, 80.25, 150.0, 300.0}) {
      const double resolution = c.linear ? 1370.0 / 65535 : 0.01;
      EXPECT_NEAR(*c.decode(c.encode(t)).value, t, resolution / 2 + 1e-12) << profile << " at " << t;
    }
  }
}

TEST(RegisterBlocks, MergesNeighboursAndSplitsFunctions) {
  std::vector<ModbusChannel> channels;
  for (int i = 0; i < 8; ++i) channels.push_back(profile_input_channel("icpdas-m7018", i, "K"));
  channels.push_back(profile_cold_junction_channel("icpdas-m7018"));
  ModbusChannel holding;
  holding.address = 5;
  holding.type = DataType::kFloat32;
  channels.push_back(holding);
  const auto blocks = plan_register_blocks(channels);
  ASSERT_EQ(blocks.size(), 3u);
  EXPECT_EQ(blocks[0].function, RegisterKind::kHolding);
  EXPECT_EQ(blocks[0].count, 2);
  EXPECT_EQ(blocks[1].address, 0);
  EXPECT_EQ(blocks[1].count, 8);
  EXPECT_EQ(blocks[2].address, 128);
  EXPECT_EQ(blocks[2].count, 1);
}

}  // namespace
}  // namespace bosfuse::acquisition
