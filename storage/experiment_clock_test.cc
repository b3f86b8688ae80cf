#include "storage/experiment_clock.h"

#include <gtest/gtest.h>

#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

constexpr std::int64_t kStart = 1'795'000'000'000'000'000;  // 2026-11-18T11:06:40Z

RunStore make_run(const std::filesystem::path& dir, double time_scale, std::optional<std::string> origin) {
  RunInfo info{0, "clock", kStart, std::nullopt, "", RunStatus::kRunning, time_scale, std::move(origin)};
  auto store = RunStore::create(dir, info, RunStore::CreateMode::kNew);
  const auto device = store.add_device({0, "d", "modbus-tcp", "generic", "x"});
  const auto channel = store.add_channel({0, device, "tc", "thermocouple", "degC", "K", std::nullopt, std::nullopt});
  const Sample first{channel, kStart + 2'000'000'000, std::nullopt, std::nullopt, std::nullopt, SampleStatus::kTimeout};
  const Sample later{channel, kStart + 3'000'000'000, std::nullopt, 40.0, 40.0, SampleStatus::kOk};
  store.write_samples(std::vector<Sample>{first, later});
  return store;
}

TEST(ExperimentClock, WithoutADeclaredOriginCountsFromTheFirstSampleOfAnyStatus) {
  testing::TempDir dir;
  const auto store = make_run(dir / "run", 1, std::nullopt);
  const auto clock = experiment_clock(store);
  EXPECT_EQ(clock.origin_ns, kStart + 2'000'000'000);
  EXPECT_DOUBLE_EQ(clock.seconds(kStart + 3'500'000'000), 1.5);
  EXPECT_DOUBLE_EQ(clock.seconds(kStart), -2.0) << "before the origin: negative";
  EXPECT_EQ(clock.basis(), "experiment seconds since the first sample (2026-11-18T11:06:42.000Z)");
  EXPECT_TRUE(clock.note.empty());
}

TEST(ExperimentClock, ADeclaredMarkerIsTheOriginAndTheScaleStretchesTheRecord) {
  testing::TempDir dir;
  auto store = make_run(dir / "run", 16, "heater off");
  const Event marker{0, std::nullopt, kStart + 2'500'000'000, "marker", "heater off"};
  const Event other{0, std::nullopt, kStart + 1'000'000'000, "marker", "fan on"};
  store.write_events(std::vector<Event>{other, marker});
  const auto clock = experiment_clock(store);
  EXPECT_EQ(clock.origin_ns, kStart + 2'500'000'000);
  EXPECT_DOUBLE_EQ(clock.seconds(kStart + 3'500'000'000), 16.0) << "one recorded second is 16 experiment seconds";
  EXPECT_EQ(clock.to_ns(16.0), kStart + 3'500'000'000);
  EXPECT_NE(clock.basis().find("since heater off (2026-11-18T11:06:42.500Z); recorded at 16"), std::string::npos)
      << clock.basis();
}

TEST(ExperimentClock, AMissingDeclaredMarkerFallsBackToTheFirstSampleAndSaysSo) {
  testing::TempDir dir;
  const auto store = make_run(dir / "run", 1, "heater off");
  const auto clock = experiment_clock(store);
  EXPECT_EQ(clock.origin_ns, kStart + 2'000'000'000);
  EXPECT_NE(clock.note.find("\"heater off\" is not among the run's marker events"), std::string::npos) << clock.note;
}

TEST(ExperimentClock, ARunStoresItsScaleAndOriginAndRefusesANonPositiveScale) {
  testing::TempDir dir;
  make_run(dir / "run", 2.5, "heater off");
  const auto run = RunStore::open(dir / "run").run();
  EXPECT_DOUBLE_EQ(run.time_scale, 2.5);
  EXPECT_EQ(run.origin_event, "heater off");
  EXPECT_THROW(make_run(dir / "bad", 0, std::nullopt), StorageError);
}

}  // namespace
}  // namespace bosfuse::storage
