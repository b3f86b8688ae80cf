// One experiment, one run: thermocouples from a simulated Modbus module on
// loopback and frames from a folder a "camera" writes into during the run,
// both stamped on the host clock and stored side by side.

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "sim/modbus_server.h"
#include "tests/support/forged_image.h"
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

// The camera writes a frame padded to 1.9 GB and half a JPEG between good
// frames: each bad one is a lost frame, counted and recorded as an event
// naming its file, while the good frames and the thermocouples go on being
// logged and the run ends as it should.
TEST(CameraLogging, AFrameFileThatCannotBeReadIsALostFrameAndLoggingGoesOn) {
  TempDir dir;
  const auto shots = dir.path() / "dslr";
  std::filesystem::create_directory(shots);
  sim::ModbusSimServer server(module_options("adam-6018", 1, loopback_tcp()));
  server.start();
  const std::string toml = "[run]\nname = \"lossy\"\n" + tcp_device_toml("adam", server.port(), 1, 0.1) +
                           "[[cameras]]\nname = \"dslr\"\nsource = \"folder\"\nfolder = \"" + shots.string() +
                           "\"\nsettle_s = 0.1\n";
  auto config = acquisition::parse_experiment(toml, "lossy.toml");
  config.cameras.at(0).folder.give_up_after = 500ms;  // how long half a JPEG may still be being written
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);

  const std::vector<std::uint8_t> jpeg = encoded(textured_frame(2, CV_8U, {320, 240}), ".jpg");
  std::thread camera([&] {
    std::this_thread::sleep_for(300ms);
    write_file(shots / "IMG_0.png", encoded(textured_frame(0), ".png"));
    write_padded(shots / "IMG_1.png", encoded(textured_frame(1), ".png"), 1'900'000'000);
    write_file(shots / "IMG_2.jpg", std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + jpeg.size() / 2));
    std::this_thread::sleep_for(300ms);
    write_file(shots / "IMG_3.png", encoded(textured_frame(3), ".png"));
  });
  const auto summary = log_for(store, config, 3000ms);
  camera.join();
  server.stop();

  ASSERT_EQ(summary.cameras.size(), 1u);
  EXPECT_EQ(summary.cameras[0].stats.frames, 2);
  EXPECT_EQ(summary.cameras[0].stats.failures, 2);
  EXPECT_TRUE(summary.complete());
  ASSERT_EQ(store.frames().size(), 2u);
  std::vector<std::string> lost;
  for (const auto& event : store.events()) {
    if (event.kind == "error") lost.push_back(event.message);
  }
  ASSERT_EQ(lost.size(), 2u);
  EXPECT_NE(lost[0].find("IMG_1.png: the file is 1900000000 bytes"), std::string::npos) << lost[0];
  EXPECT_NE(lost[1].find("IMG_2.jpg never became a complete image"), std::string::npos) << lost[1];
  EXPECT_NE(lost[1].find("Premature end of JPEG file"), std::string::npos) << lost[1];
  EXPECT_GE(store.read_samples(store.channels().at(0).id).size(), 15u) << "the thermocouple was logged throughout";
}

}  // namespace
}  // namespace bosfuse
