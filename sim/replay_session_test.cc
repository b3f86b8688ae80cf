#include "sim/replay_session.h"

#include <gtest/gtest.h>

#include <chrono>

#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

constexpr std::int64_t kStartNs = 1'000'000'000'000'000'000;

// A closed run of one module: `samples` readings of one thermocouple 100 ms
// apart, and the marker of its origin at its start.
void recorded_module_run(const std::filesystem::path& dir, int samples) {
  storage::RunInfo info;
  info.name = "recorded";
  info.started_ns = kStartNs;
  auto store = storage::RunStore::create(dir, info, storage::RunStore::CreateMode::kNew);
  const storage::Event origin{0, std::nullopt, kStartNs, "marker", "heater off"};
  store.write_events({&origin, 1});
  if (samples == 0) return;
  const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
  const auto channel = store.add_channel({0, device, "tc", "thermocouple", "degC", "K", {}, {}});
  std::vector<storage::Sample> series;
  for (int i = 0; i < samples; ++i) {
    series.push_back({channel, kStartNs + 100'000'000LL * (i + 1), {}, 60.0 - i, {}, storage::SampleStatus::kOk});
  }
  store.write_samples(series);
  store.finish(storage::RunStatus::kComplete, kStartNs + 100'000'000LL * (samples + 1));
}

TEST(ReplaySession, ReplaysEverySampleAndTheMarkersIntoTheNewRun) {
  testing::TempDir dir;
  recorded_module_run(dir / "recorded", 5);
  ReplaySession session(dir / "recorded", dir / "replay", 4);
  EXPECT_EQ(session.dir(), dir / "replay");
  const std::atomic<bool> interrupted{false};
  const auto summary = session.run(interrupted);
  EXPECT_TRUE(summary.complete());
  EXPECT_THROW(session.run(interrupted), std::logic_error);

  const auto replay = storage::RunStore::open(dir / "replay");
  ASSERT_EQ(replay.channels().size(), 1u);
  const auto samples = replay.read_samples(replay.channels()[0].id);
  ASSERT_EQ(samples.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(samples[i].value, 60.0 - i) << i;
    EXPECT_EQ(samples[i].t_ns - samples[0].t_ns, 25'000'000LL * i) << "the recording's times, scaled, " << i;
  }
  const auto events = replay.events();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().message, "heater off");
}

TEST(ReplaySession, AnInterruptionEndsTheReplayAtOnce) {
  testing::TempDir dir;
  recorded_module_run(dir / "recorded", 600);  // a minute recorded
  ReplaySession session(dir / "recorded", dir / "replay", 1);
  const std::atomic<bool> interrupted{true};
  const auto started = std::chrono::steady_clock::now();
  session.run(interrupted);
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(5));
}

TEST(ReplaySession, ARunWithNothingToReplayIsRefused) {
  testing::TempDir dir;
  recorded_module_run(dir / "recorded", 0);
  try {
    ReplaySession session(dir / "recorded", dir / "replay", 1);
    FAIL() << "replayed a run without devices or frames";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to replay"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "replay"));
}

}  // namespace
}  // namespace bosfuse::sim
