// The simulated GenICam camera read back through the real GenICam source
// over GigE Vision on 127.0.0.1: the scene's frames at its size, the first
// without flow (the same image the scene renders), the later ones with it,
// each with the camera's timestamp and its arrival. GigE Vision's control
// port is fixed (3956): these tests hold the ctest lock genicam_gvcp
// (sim/CMakeLists.txt).

#include "sim/simulated_genicam_camera.h"

#include <gtest/gtest.h>

#include "acquisition/cameras/genicam_source.h"
#include "sim/demo_setup.h"

namespace bosfuse::sim {
namespace {

using namespace std::chrono_literals;

BackgroundPattern simgc_test_pattern(const DemoSetup& setup) {
  PatternOptions pattern;
  pattern.width_px = setup.scene.width_px;
  pattern.height_px = setup.scene.height_px;
  pattern.dot_diameter_px = 3;
  pattern.seed = 5;
  return generate_pattern(pattern);
}

TEST(SimulatedGenicamCamera, ServesTheSceneThroughTheGenicamSource) {
  const DemoSetup setup = demo_setup(60);
  SimulatedGenicamCameraOptions options;
  options.frame_rate_hz = 10;
  options.speed = 10;
  const BackgroundPattern pattern = simgc_test_pattern(setup);
  SimulatedGenicamCamera camera(setup.model, pattern, CameraModel{}, options);

  acquisition::GenicamOptions source_options;
  source_options.device = options.address;
  source_options.pixel_format = "Mono8";
  source_options.frame_rate_hz = options.frame_rate_hz;
  acquisition::GenicamSource source(source_options);
  source.connect();
  EXPECT_EQ(source.streaming().width_px, setup.scene.width_px);
  EXPECT_EQ(source.streaming().height_px, setup.scene.height_px);
  std::vector<acquisition::CapturedFrame> frames;
  for (int i = 0; i < 100 && frames.size() < 3; ++i) {  // bounded: 100 waits of at most 500 ms
    if (auto frame = source.next(500ms)) frames.push_back(std::move(*frame));
  }
  source.disconnect();
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_GE(camera.frames_rendered(), 3u);
  // The first frame the camera filled is the reference; the source may
  // have joined after it, so compare against the background rendering.
  const cv::Mat reference = setup.model->render_frame(pattern, CameraModel{}, 0, false, 0);
  for (const auto& f : frames) {
    EXPECT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(f.image.size(), reference.size());
    ASSERT_TRUE(f.device_t_ns);
    ASSERT_TRUE(f.arrival_ns);
    EXPECT_GT(*f.arrival_ns, 0);
    cv::Scalar mean, std_dev;
    cv::meanStdDev(f.image, mean, std_dev);
    EXPECT_GT(std_dev[0], 0.05 * 255) << "the background's dots, not a blank frame";
  }
  // The first frame filled is the background without flow, as the scene renders it.
  if (camera.frames_rendered() > 0 && frames[0].image.size() == reference.size()) {
    EXPECT_LT(cv::norm(frames[0].image, reference, cv::NORM_INF), 1.0 + 1e-9)
        << "frame 0 is the scene's reference rendering";
  }
  EXPECT_LT(*frames[0].device_t_ns, *frames[1].device_t_ns);
  EXPECT_LT(*frames[1].device_t_ns, *frames[2].device_t_ns);
  // Camera time is host time: the arrival follows the stamp by a frame's transfer at most.
  EXPECT_NEAR(static_cast<double>(*frames[2].arrival_ns - *frames[2].device_t_ns), 0, 1e9);
  // Later frames show the scene with its flow: they differ from the background.
  EXPECT_GT(cv::norm(frames[2].image, reference, cv::NORM_L1), 0);
}

TEST(SimulatedGenicamCamera, RefusesInvalidOptionsAndATakenPort) {
  SimulatedGenicamCameraOptions options;
  options.frame_rate_hz = 0.5;
  EXPECT_NE(options.Validate().find("frame rate"), std::string::npos);
  options.frame_rate_hz = 5;
  options.serial.clear();
  EXPECT_NE(options.Validate().find("serial"), std::string::npos);
  const DemoSetup setup = demo_setup(30);
  SimulatedGenicamCamera first(setup.model, simgc_test_pattern(setup), CameraModel{}, {});
  EXPECT_THROW(SimulatedGenicamCamera(setup.model, simgc_test_pattern(setup), CameraModel{}, {}), std::runtime_error);
}

}  // namespace
}  // namespace bosfuse::sim
