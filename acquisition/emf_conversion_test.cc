// Millivolt channels turned into temperatures with cold-junction
// compensation in voltage.

#include "acquisition/emf_conversion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

double reference_emf_mv(ThermocoupleType type, double t_c) { return emf_mv_at(type, t_c).emf_mv.value(); }

// A device with a millivolt input and its terminal-block temperature.
class MillivoltModule : public ThermocoupleSource {
 public:
  std::vector<ChannelReading> next;
  storage::DeviceInfo device_info() const override { return {0, "mv", "test", "", ""}; }
  std::vector<storage::ChannelInfo> channel_infos() const override {
    return {{0, 0, "hot", "voltage", "mV", {}, {}, {}}, {0, 0, "terminals", "cold-junction", "degC", {}, {}, {}}};
  }
  void connect() override {}
  void disconnect() override {}
  std::vector<ChannelReading> read() override { return next; }
};

TEST(EmfConversion, CompensatesWithTheColdJunctionChannelInVoltage) {
  const auto k = ThermocoupleType::kK;
  const double measured = reference_emf_mv(k, 300.0) - reference_emf_mv(k, 24.0);  // what the terminals at 24 °C see
  auto module = std::make_unique<MillivoltModule>();
  module->next = {{measured, measured, SampleStatus::kOk}, {24.0, 2400, SampleStatus::kOk}};
  EmfConvertingSource source(std::move(module), {EmfInput{k, "terminals", std::nullopt}, std::nullopt});
  const auto readings = source.read();
  EXPECT_NEAR(readings[0].value.value_or(NAN), 300.0, 1e-6);
  EXPECT_DOUBLE_EQ(readings[0].raw, measured);
  EXPECT_DOUBLE_EQ(readings[1].value.value_or(NAN), 24.0);  // untouched
  // Adding temperatures instead of EMFs would be off by about a degree here.
  EXPECT_GT(std::abs(temperature_c_at(k, measured).temperature_c.value() + 24.0 - 300.0), 0.5);
  const auto infos = source.channel_infos();
  EXPECT_EQ(infos[0].unit, "degC");
  EXPECT_EQ(infos[0].tc_type, "K");
}

TEST(EmfConversion, FixedColdJunctionAndStatuses) {
  const auto t = ThermocoupleType::kT;
  std::vector<EmfConversion> conversions = {{0, {t, "", 0.0}, std::nullopt}, {1, {t, "", 20.0}, std::nullopt}};
  std::vector<ChannelReading> readings = {{reference_emf_mv(t, 55.5), 0, SampleStatus::kOk}, {100.0, 0, SampleStatus::kOk}};
  convert_emf_readings(conversions, readings);
  EXPECT_NEAR(readings[0].value.value_or(NAN), 55.5, 1e-6);
  EXPECT_EQ(readings[1].status, SampleStatus::kOutOfRange);  // 100 mV is beyond type T
  EXPECT_FALSE(readings[1].value.has_value());

  std::vector<ChannelReading> open = {{std::nullopt, 65535, SampleStatus::kOpenCircuit}, {}};
  convert_emf_readings(conversions, open);
  EXPECT_EQ(open[0].status, SampleStatus::kOpenCircuit);  // the device's own verdict stays
}

TEST(EmfConversion, MissingColdJunctionReadingMeansNoTemperature) {
  auto module = std::make_unique<MillivoltModule>();
  module->next = {{1.0, 1.0, SampleStatus::kOk}, {std::nullopt, 0, SampleStatus::kTimeout}};
  EmfConvertingSource source(std::move(module), {EmfInput{ThermocoupleType::kK, "terminals", {}}, std::nullopt});
  EXPECT_EQ(source.read()[0].status, SampleStatus::kInvalidValue);
  EXPECT_THROW(EmfConvertingSource(std::make_unique<MillivoltModule>(), {EmfInput{ThermocoupleType::kK, "nope", {}}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::acquisition
