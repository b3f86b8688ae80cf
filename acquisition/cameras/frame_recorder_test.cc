// The recorder against a scripted camera: lossless files at the camera's bit
// depth, reference frames, frames in the run store, and a camera that fails.

#include "acquisition/cameras/frame_recorder.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "acquisition/clock.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;

// Yields a fixed list of frames, one per call; `fail_at` makes that call throw
// DeviceError once, `flapping_until` every odd call before it.
class ScriptedCamera : public FrameSource {
 public:
  std::vector<cv::Mat> frames;
  int fail_at = -1;
  int flapping_until = 0;

  std::string kind() const override { return "virtual"; }
  std::string describe() const override { return "scripted camera"; }
  void connect() override {}
  void disconnect() override {}
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override {
    const int call = calls_++;
    if (call == fail_at || (call < flapping_until && call % 2 == 1)) throw DeviceError("cable pulled");
    if (next_ >= frames.size()) {
      std::this_thread::sleep_for(wait);
      return std::nullopt;
    }
    return CapturedFrame{frames[next_++], utc_now_ns(), std::nullopt, "scripted", std::nullopt, std::nullopt};
  }

 private:
  std::size_t next_ = 0;
  int calls_ = 0;
};

struct Harness {
  testing::TempDir dir;
  storage::RunStore store =
      storage::RunStore::create(dir / "run", {0, "t", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                storage::RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "cam", "camera", "virtual", ""});

  FrameRecorder::Stats record(std::unique_ptr<ScriptedCamera> camera, FrameRecorderOptions options,
                              std::size_t expected_frames) {
    storage::RunWriter writer(store, {20ms, 10'000});
    const auto recorder =
        std::make_shared<FrameRecorder>(std::move(camera), "cam", device, store.dir(), writer, options);
    recorder->start();
    for (int i = 0; i < 300 && recorder->stats().frames < static_cast<std::int64_t>(expected_frames); ++i) {
      std::this_thread::sleep_for(10ms);
    }
    EXPECT_TRUE(recorder->stop());
    writer.flush();
    return recorder->stats();
  }
};

FrameRecorderOptions fast_options() {
  FrameRecorderOptions options;
  options.interval = 20ms;
  options.backoff = {20ms, 100ms};
  return options;
}

TEST(FrameRecorder, StoresLosslessFramesAtTheirBitDepthWithTheFirstAsReference) {
  Harness h;
  auto camera = std::make_unique<ScriptedCamera>();
  camera->frames = {testing::textured_frame(0, CV_16U), testing::textured_frame(1, CV_16U),
                    testing::textured_frame(2, CV_8UC3)};
  const auto originals = camera->frames;
  const auto stats = h.record(std::move(camera), fast_options(), 3);
  EXPECT_EQ(stats.frames, 3);
  const auto frames = h.store.frames();
  ASSERT_EQ(frames.size(), 3u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].is_reference, i == 0);
    EXPECT_EQ(frames[i].bit_depth, i < 2 ? 16 : 8);
    EXPECT_EQ(frames[i].path, "frames/cam/00000" + std::to_string(i) + ".png");
    const cv::Mat stored = cv::imread((h.store.dir() / frames[i].path).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(stored.type(), originals[i].type());
    EXPECT_EQ(cv::norm(stored, originals[i], cv::NORM_INF), 0.0) << "frame " << i;
  }
  for (const auto& entry : std::filesystem::directory_iterator(h.store.dir() / "frames/cam")) {
    EXPECT_EQ(entry.path().string().find("partial"), std::string::npos) << entry.path();
  }
}

TEST(FrameRecorder, AFramePngCannotHoldIsReportedByTypeAndTheNextIsStored) {
  Harness h;
  auto camera = std::make_unique<ScriptedCamera>();
  camera->frames = {cv::Mat(48, 64, CV_32F, cv::Scalar(0.5)), testing::textured_frame(1, CV_16U)};
  const auto stats = h.record(std::move(camera), fast_options(), 1);
  EXPECT_EQ(stats.frames, 1);
  EXPECT_EQ(stats.failures, 1);
  const auto frames = h.store.frames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].bit_depth, 16);
  bool reported = false;
  for (const auto& e : h.store.events()) reported |= e.kind == "error" && e.message.find("32FC1") != std::string::npos;
  EXPECT_TRUE(reported) << "no error event naming the frame's type";
  for (const auto& entry : std::filesystem::directory_iterator(h.store.dir() / "frames/cam")) {
    EXPECT_EQ(entry.path().string().find("partial"), std::string::npos) << entry.path();
  }
}

TEST(FrameRecorder, FramesTakenWhileFlaggedAreReferences) {
  Harness h;
  auto camera = std::make_unique<ScriptedCamera>();
  camera->frames = {testing::textured_frame(0), testing::textured_frame(1)};
  FrameRecorderOptions options = fast_options();
  options.reference_frames = 0;
  options.reference_flag = h.dir.path() / "reference.flag";
  testing::write_file(options.reference_flag, {});
  h.record(std::move(camera), options, 2);
  for (const auto& frame : h.store.frames()) EXPECT_TRUE(frame.is_reference);
}

TEST(FrameRecorder, FailingCameraIsRecordedAndReopened) {
  Harness h;
  auto camera = std::make_unique<ScriptedCamera>();
  camera->frames = {testing::textured_frame(0), testing::textured_frame(1)};
  camera->fail_at = 1;
  const auto stats = h.record(std::move(camera), fast_options(), 2);
  EXPECT_EQ(stats.frames, 2);
  EXPECT_EQ(stats.failures, 1);
  std::vector<std::string> kinds;
  for (const auto& e : h.store.events()) kinds.push_back(e.kind);
  EXPECT_EQ(kinds, (std::vector<std::string>{"connect", "disconnect", "reconnect"}));
}

// Debounce, as for a thermocouple reader: a camera failing every other
// frame is one outage, ended once recovery_frames frames came in a row.
TEST(FrameRecorder, ACameraFailingEveryOtherFrameIsOneOutage) {
  Harness h;
  auto camera = std::make_unique<ScriptedCamera>();
  for (int i = 0; i < 8; ++i) camera->frames.push_back(testing::textured_frame(i));
  camera->flapping_until = 12;  // calls 1, 3, ... 11 fail
  const auto stats = h.record(std::move(camera), fast_options(), 8);
  EXPECT_EQ(stats.frames, 8);
  EXPECT_EQ(stats.failures, 6);
  std::vector<std::string> kinds;
  for (const auto& e : h.store.events()) kinds.push_back(e.kind);
  EXPECT_EQ(kinds, (std::vector<std::string>{"connect", "disconnect", "reconnect"}));
  EXPECT_NE(h.store.events().back().message.find("(6 failed polls)"), std::string::npos)
      << h.store.events().back().message;
}

}  // namespace
}  // namespace bosfuse::acquisition
