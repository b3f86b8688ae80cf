// One experiment, one run: thermocouples from a simulated Modbus module on
// loopback and frames from a folder a "camera" writes into during the run,
// both stamped on the host clock and stored side by side.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "sim/modbus_server.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"

namespace bosfuse {
namespace {

using namespace testing;
using namespace std::chrono_literals;

TEST(CameraLogging, ThermocouplesAndFramesLandInTheSameRun) {
  TempDir dir;
  const auto shots = dir.path() / "dslr";
  std::filesystem::create_directory(shots);
  sim::ModbusSimServer server(module_options("adam-6018", 2, loopback_tcp()));
  server.start();
  const std::string toml = "[run]\nname = \"fused\"\n" + tcp_device_toml("adam", server.port(), 2, 0.1) +
                           "[[cameras]]\nname = \"dslr\"\nsource = \"folder\"\nfolder = \"" + shots.string() +
                           "\"\nsettle_s = 0.1\n";
  const auto config = acquisition::parse_experiment(toml, "fused.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);

  std::vector<cv::Mat> written;
  std::thread camera([&] {
    for (int i = 0; i < 3; ++i) {
      std::this_thread::sleep_for(400ms);
      written.push_back(textured_frame(i, CV_16U));
      write_file(shots / ("IMG_" + std::to_string(i) + ".png"), encoded(written.back(), ".png"));
    }
  });
  const auto summary = log_for(store, config, 2500ms);
  camera.join();
  server.stop();

  ASSERT_EQ(summary.cameras.size(), 1u);
  EXPECT_EQ(summary.cameras[0].stats.frames, 3);
  const auto frames = store.frames();
  ASSERT_EQ(frames.size(), 3u);
  const auto samples = store.read_samples(store.channels().at(0).id);
  ASSERT_GE(samples.size(), 10u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].is_reference, i == 0);
    EXPECT_EQ(frames[i].bit_depth, 16);
    // On the thermocouples' clock: inside the span of the samples.
    EXPECT_GT(frames[i].t_ns, samples.front().t_ns);
    EXPECT_LT(frames[i].t_ns, samples.back().t_ns);
    const cv::Mat stored = cv::imread((store.dir() / frames[i].path).string(), cv::IMREAD_UNCHANGED);
    EXPECT_EQ(cv::norm(stored, written[i], cv::NORM_INF), 0.0) << frames[i].path;
  }
  std::vector<std::string> camera_devices;
  for (const auto& d : store.devices()) {
    if (d.kind == "camera") camera_devices.push_back(d.name + " " + d.profile);
  }
  EXPECT_EQ(camera_devices, std::vector<std::string>{"dslr folder"});
}

}  // namespace
}  // namespace bosfuse
