// The simulated experiment recorded through the real paths: the scene's
// thermocouples served by a Modbus module on loopback, its frames by the
// virtual camera, both landing in one run with the values the scene gives.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "acquisition/logger.h"
#include "sim/virtual_devices.h"
#include "storage/experiment_clock.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace std::chrono_literals;

TEST(VirtualExperiment, SceneThermocouplesAndFramesAreRecordedThroughTheRealPaths) {
  testing::TempDir dir;
  sim::SceneOptions options;
  options.width_px = 240;
  options.height_px = 200;
  options.cylinder_x_px = 120;
  options.cylinder_y_px = 190;
  options.px_per_mm = 4;
  options.duration_s = 200;
  options.z_d_m = 0.3;  // a background far enough behind for clear shifts at this small scale
  const auto scene = std::make_shared<const sim::ConvectionScene>(options);
  const std::vector<sim::SceneThermocouple> tcs = {{"plume", 0, 0.03, 1.0, 0.05}, {"side", 0.004, 0.03, 1.0, 0.05}};
  const double speed = 50;
  const auto table = std::make_shared<const sim::SceneThermocoupleTable>(*scene, tcs, speed, 5);
  sim::ModbusSimServer server(sim::scene_module_options(table, "adam-6018", options.ambient_c, 0));
  // The scene's t = 0 is the server's start: at most this late.
  const std::int64_t scene_start_ns = storage::utc_now_ns();
  server.start();

  const std::string toml = testing::tcp_device_toml("module", server.port(), 2, 0.05);
  auto store = storage::RunStore::create(dir / "run", testing::run_info(toml), storage::RunStore::CreateMode::kNew);
  acquisition::LoggerOptions logger_options;
  logger_options.duration = 2s;
  acquisition::Logger logger(store, logger_options);
  logger.add_devices(acquisition::parse_experiment(toml, "virtual.toml"));
  sim::PatternOptions pattern;
  pattern.width_px = options.width_px;
  pattern.height_px = options.height_px;
  acquisition::FrameRecorderOptions camera_options;
  camera_options.interval = 250ms;
  logger.add_camera(
      std::make_unique<sim::SceneCamera>(scene, sim::generate_pattern(pattern), sim::CameraModel{}, speed, 1), "camera",
      camera_options);
  std::atomic<bool> stop{false};
  const auto summary = logger.run(stop);
  server.stop();

  // Every sample the module served is the scene's reading at that moment.
  const auto served = server.served();
  const auto samples = store.read_samples(store.channels().at(0).id);
  ASSERT_GE(samples.size(), 20u);
  EXPECT_GT(*samples.front().value, *samples.back().value + 1.0);  // it cooled
  double first_served = NAN;
  double first_served_scene_s = NAN;  // the scene's time when it was served (the poll may come late on a busy machine)
  for (const auto& s : served) {
    if (s.channel == 0) {
      first_served = s.reading.value.value_or(NAN);
      first_served_scene_s = static_cast<double>(s.t_ns - scene_start_ns) * 1e-9 * speed;
      break;
    }
  }
  EXPECT_DOUBLE_EQ(*samples.front().value, first_served);
  EXPECT_NEAR(*samples.front().value, scene->temperature_c(0, 0.03, first_served_scene_s), 0.5);

  ASSERT_GE(summary.cameras.at(0).stats.frames, 5);
  const auto frames = store.frames();
  EXPECT_TRUE(frames.front().is_reference);
  EXPECT_FALSE(frames.back().is_reference);
  const cv::Mat reference = cv::imread((store.dir() / frames.front().path).string(), cv::IMREAD_UNCHANGED);
  const cv::Mat later = cv::imread((store.dir() / frames[1].path).string(), cv::IMREAD_UNCHANGED);
  // The plume moves the background where it bends light most; far to the side it does not.
  cv::Point2d strongest;
  double largest_px = 0;
  for (double x = -0.006; x <= 0.006; x += 0.0005) {
    const cv::Point2d at = scene->image_position_px(x, 0.015);
    const cv::Point2d d = scene->displacement_px(at.x, at.y, 5);
    if (std::hypot(d.x, d.y) > largest_px) largest_px = std::hypot(d.x, d.y), strongest = at;
  }
  ASSERT_GT(largest_px, 0.3);
  const cv::Rect plume(static_cast<int>(strongest.x) - 4, static_cast<int>(strongest.y) - 8, 8, 16);
  const cv::Rect aside(2, 2, 16, 16);
  cv::Mat diff;
  cv::absdiff(reference, later, diff);
  EXPECT_GT(cv::mean(diff(plume))[0], 3 * cv::mean(diff(aside))[0]);
}

}  // namespace
}  // namespace bosfuse
