#include "sim/demo_setup.h"

#include <gtest/gtest.h>

#include "acquisition/config/experiment_config.h"

namespace bosfuse::sim {
namespace {

// The logger and the processing read the demo through its experiment file:
// it must parse and place each thermocouple where the scene shows it.
TEST(DemoSetup, TheExperimentFileNamesTheThermocouplesAtTheScenesImagePositions) {
  const DemoSetup setup = demo_setup(60);
  const auto config = acquisition::parse_experiment(demo_experiment(setup, 5020, 0.0625, 16), "demo.toml");
  EXPECT_EQ(config.run_name, "demo");
  EXPECT_DOUBLE_EQ(config.time_scale, 16);
  EXPECT_EQ(config.origin_event, "heater off");
  ASSERT_EQ(config.modbus_devices.size(), 1u);
  const auto& device = config.modbus_devices[0];
  EXPECT_EQ(device.endpoint.port, 5020);
  EXPECT_EQ(device.poll_period, std::chrono::nanoseconds(62'500'000));
  ASSERT_EQ(device.channels.size(), setup.thermocouples.size());
  for (std::size_t i = 0; i < setup.thermocouples.size(); ++i) {
    const SceneThermocouple& tc = setup.thermocouples[i];
    const cv::Point2d at = setup.model->image_position_px(tc.x_m, tc.z_m);
    const auto& channel = device.channels[i];
    EXPECT_EQ(channel.name, tc.name);
    ASSERT_TRUE(channel.image_x_px && channel.image_y_px) << tc.name;
    EXPECT_NEAR(*channel.image_x_px, at.x, 0.005) << tc.name;  // written to 0.01 px
    EXPECT_NEAR(*channel.image_y_px, at.y, 0.005) << tc.name;
    EXPECT_EQ(channel.time_constant_s, tc.lag_s) << tc.name;
  }
}

TEST(DemoSetup, IsThePaperSetUpAtTheDemosScale) {
  const DemoSetup setup = demo_setup(240);
  EXPECT_EQ(setup.scene.width_px, 480);
  EXPECT_EQ(setup.scene.height_px, 440);
  EXPECT_DOUBLE_EQ(setup.scene.duration_s, 270) << "the cooling and a margin";
  const cv::Point2d lower = setup.model->image_position_px(0, 0.035);
  EXPECT_DOUBLE_EQ(lower.x, 240);
  EXPECT_DOUBLE_EQ(lower.y, 420 - 35 * 8);
}

TEST(DemoOptions, CountTheFramesAfterTheReferenceAndRefuseWhatCannotRun) {
  DemoOptions options;
  EXPECT_EQ(options.Validate(), "");
  EXPECT_EQ(options.frames_after_reference(), 24);
  options.experiment_s = 30;
  EXPECT_EQ(options.frames_after_reference(), 3) << "a BOS fit needs " << kFramesForABosFit;
  options.speed = 0;
  EXPECT_NE(options.Validate(), "");
  options.speed = 16;
  options.frame_interval_s = -1;
  EXPECT_NE(options.Validate(), "");
}

}  // namespace
}  // namespace bosfuse::sim
