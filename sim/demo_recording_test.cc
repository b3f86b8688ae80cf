#include "sim/demo_recording.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

// 20 s of cooling at 16×: a recording of 1.25 s, a reference and two frames.
DemoOptions short_demo() {
  DemoOptions options;
  options.experiment_s = 20;
  options.seed = 3;
  return options;
}

TEST(DemoRecording, AShortDemoStoresTheThermocouplesTheFramesAndTheOrigin) {
  testing::TempDir dir;
  const DemoOptions options = short_demo();
  const DemoSetup setup = demo_setup(options.experiment_s);
  std::vector<std::string> notes;
  int runs_created = 0;
  DemoRecordingHooks hooks;
  hooks.note = [&](const std::string& line) { notes.push_back(line); };
  hooks.run_created = [&] { runs_created += std::filesystem::exists(dir / "run" / "run.sqlite"); };
  const auto summary = record_demo(options, setup, dir / "run", hooks);
  EXPECT_TRUE(summary.complete());
  EXPECT_EQ(runs_created, 1) << "once, with the run's store in place";
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& line) {
    return line.starts_with("demo: simulating 20 s of cooling");
  }));

  const auto store = storage::RunStore::open(dir / "run");
  const auto channels = store.channels();
  ASSERT_EQ(channels.size(), setup.thermocouples.size());
  for (const auto& channel : channels) {
    const auto samples = store.read_samples(channel.id);
    EXPECT_GE(samples.size(), 10u) << channel.name << ": one a second of experiment time";
    ASSERT_FALSE(samples.empty());
    EXPECT_GT(*samples.front().value, setup.scene.ambient_c + 5) << channel.name << " is in the plume";
  }
  const auto frames = store.frames();
  ASSERT_GE(frames.size(), 2u);
  EXPECT_TRUE(frames.front().is_reference);
  EXPECT_FALSE(frames.back().is_reference);
  const auto events = store.events();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().message, "heater off");
}

TEST(DemoRecording, ASetStopFlagEndsItAtOnce) {
  testing::TempDir dir;
  const DemoOptions options = short_demo();
  const std::atomic<bool> stop{true};
  DemoRecordingHooks hooks;
  hooks.stop = &stop;
  const auto summary = record_demo(options, demo_setup(options.experiment_s), dir / "run", hooks);
  EXPECT_LT(summary.elapsed_s, 1.0);
}

TEST(DemoRecording, InvalidOptionsAreRefusedBeforeAnythingIsRecorded) {
  testing::TempDir dir;
  DemoOptions options = short_demo();
  options.speed = 0;
  EXPECT_THROW(record_demo(options, demo_setup(20), dir / "run", {}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir / "run"));
}

}  // namespace
}  // namespace bosfuse::sim
