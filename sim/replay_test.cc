#include "sim/replay.h"

#include <gtest/gtest.h>

#include "acquisition/config/experiment_config.h"
#include "storage/run_store.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

// Names a run store may hold: control characters, tab, newline, quotes,
// backslashes, TOML syntax and non-ASCII.
const std::vector<std::string> kAwkwardNames = {
    "tc\x01one",     "tab\there",      "line\nbreak",          "say \"hi\"",
    "back\\slash\\", "Ofen 1 – Δ°C µ", "]] [x]\nname = \"y\"", "'single' ''' \"\"\"",
    "trailing\\"};

RecordedRun awkward_run() {
  RecordedRun run;
  run.dir = "/runs/a \"quoted\"\nfolder";
  run.run.name = "run\x1f \"x\" \\ \u00e9";
  ReplayDevice device;
  device.name = "dev\x7f\t\"adam\"";
  for (std::size_t i = 0; i < kAwkwardNames.size(); ++i) {
    storage::ChannelInfo channel;
    channel.name = kAwkwardNames[i];
    channel.kind = "thermo\"couple";
    channel.unit = "\u00b0C\b";
    device.channels.push_back(channel);
    device.samples.push_back({storage::Sample{}});
  }
  run.devices.push_back(device);
  run.cameras = {"cam_1"};  // camera names are restricted: they name the frame folder
  return run;
}

TEST(ReplayExperiment, AnyNameRoundTripsThroughTheExperimentFile) {
  const RecordedRun run = awkward_run();
  const std::string toml = replay_experiment_toml(run, {5020}, 2.0);
  const auto config = acquisition::parse_experiment(toml, "replay.toml");
  EXPECT_EQ(config.run_name, "replay of " + run.run.name);
  ASSERT_EQ(config.modbus_devices.size(), 1u);
  const auto& device = config.modbus_devices.front();
  EXPECT_EQ(device.name, run.devices[0].name);
  ASSERT_EQ(device.channels.size(), kAwkwardNames.size());
  for (std::size_t i = 0; i < kAwkwardNames.size(); ++i) {
    EXPECT_EQ(device.channels[i].name, kAwkwardNames[i]);
    EXPECT_EQ(device.channels[i].kind, run.devices[0].channels[i].kind);
    EXPECT_EQ(device.channels[i].unit, run.devices[0].channels[i].unit);
  }
  ASSERT_EQ(config.cameras.size(), 1u);
  EXPECT_EQ(config.cameras[0].name, run.cameras[0]);
  EXPECT_EQ(config.cameras[0].replay_camera, run.cameras[0]);
}

// What processing reads of the recorded experiment file goes into the
// replay's: the agreement's margins and each thermocouple's time constant
// (keyed by the channel's name, whatever its letter case there), besides
// the geometry and alignment; a channel without one stays without.
TEST(ReplayExperiment, KeepsTheAgreementMarginsAndEachChannelsTimeConstant) {
  RecordedRun run;
  run.dir = "/runs/recorded";
  run.run.name = "cooling";
  ReplayDevice device;
  device.name = "adam";
  for (const char* name : {"TC_near", "tc_far", "tc_none"}) {
    storage::ChannelInfo channel;
    channel.name = name;
    channel.kind = "thermocouple";
    channel.unit = "degC";
    device.channels.push_back(channel);
    device.samples.push_back({storage::Sample{}});
  }
  run.devices.push_back(device);
  run.run.config_toml = R"([run]
name = "cooling"
[geometry]
z_d_m = 0.5
[agreement]
margin_c = 0.25
margin_k_relative = 0.02
[[devices]]
name = "adam"
profile = "generic"
transport = "tcp"
host = "127.0.0.1"
port = 502
channels = [
  { name = "tc_near", register = "holding", address = 0, type = "float32", time_constant_s = 1.75 },
  { name = "tc_far", register = "holding", address = 2, type = "float32", time_constant_s = 0.5 },
  { name = "tc_none", register = "holding", address = 4, type = "float32" },
]
)";
  const auto recorded = acquisition::parse_experiment(run.run.config_toml, "recorded.toml");
  ASSERT_EQ(acquisition::channel_time_constants(recorded).size(), 2u) << "the recorded file states two";
  const auto replayed = acquisition::parse_experiment(replay_experiment_toml(run, {5020}, 4.0), "replay.toml");
  EXPECT_EQ(replayed.agreement.margin_c, 0.25);
  EXPECT_EQ(replayed.agreement.margin_k_relative, 0.02);
  const auto time_constants = acquisition::channel_time_constants(replayed);
  EXPECT_EQ(time_constants, acquisition::channel_time_constants(recorded));
  ASSERT_EQ(replayed.modbus_devices.size(), 1u);
  const auto& channels = replayed.modbus_devices[0].channels;
  ASSERT_EQ(channels.size(), 3u);
  EXPECT_EQ(channels[0].time_constant_s, 1.75);
  EXPECT_EQ(channels[1].time_constant_s, 0.5);
  EXPECT_FALSE(channels[2].time_constant_s.has_value());
}

// A recorded file that does not parse gives the replay nothing to copy,
// and the replay still has its devices.
TEST(ReplayExperiment, ARecordedFileThatDoesNotParseGivesNothingToCopy) {
  RecordedRun run = awkward_run();
  run.run.config_toml = "[agreement\nmargin_c = 0.25";
  const auto replayed = acquisition::parse_experiment(replay_experiment_toml(run, {5020}, 1.0), "replay.toml");
  EXPECT_EQ(replayed.agreement.margin_c, acquisition::AgreementMargins{}.margin_c);
  ASSERT_EQ(replayed.modbus_devices.size(), 1u);
  EXPECT_EQ(replayed.modbus_devices[0].channels.size(), kAwkwardNames.size());
}

// Found by fuzzing: a damaged store whose times lie centuries apart made
// the replay's offsets overflow. It is refused, saying why.
TEST(InspectRecordedRun, TimesCenturiesApartAreRefusedAsDamaged) {
  testing::TempDir dir;
  {
    auto store = storage::RunStore::create(
        dir / "run",
        {0, "damaged", -9'000'000'000'000'000'000, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
        storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    const storage::Sample samples[] = {{channel, 9'000'000'000'000'000'000, {}, 20.0, {}, storage::SampleStatus::kOk},
                                       {channel, 9'000'000'001'000'000'000, {}, 20.0, {}, storage::SampleStatus::kOk}};
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, 0);
  }
  try {
    inspect_recorded_run(dir / "run");
    FAIL() << "a run with damaged times was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("the run's times are damaged"), std::string::npos) << e.what();
  }
}

// A loaded logger skipped a poll (a 2 s gap in a 1 s record) and the device
// was away for a minute: the replay polls at the mean interval of the
// record without the outage, so the skipped poll does not compress time.
TEST(InspectRecordedRun, TheReplayPeriodIsTheMeanIntervalWithoutOutages) {
  testing::TempDir dir;
  {
    auto store = storage::RunStore::create(dir / "run", {0, "gaps", 0, {}, "", storage::RunStatus::kRunning, 1.0, {}},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    std::vector<storage::Sample> samples;
    for (const double t_s : {0.0, 1.0, 2.0, 4.0, 5.0, 6.0, 66.0, 67.0}) {
      samples.push_back({channel, static_cast<std::int64_t>(t_s * 1e9), {}, 20.0, {}, storage::SampleStatus::kOk});
    }
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, 67'000'000'000);
  }
  const RecordedRun run = inspect_recorded_run(dir / "run");
  ASSERT_EQ(run.devices.size(), 1u);
  // Gaps 1, 1, 2, 1, 1, (60 left out), 1: mean 7/6 s.
  EXPECT_NEAR(std::chrono::duration<double>(run.devices[0].period).count(), 7.0 / 6.0, 1e-9);
}

// Found by fuzzing: samples 99 years apart (within the century a run may
// span) made three times the median gap overflow, which left no gap to
// average and the period NaN. The period is the one gap, and the replay
// polls at the longest period the logger accepts.
TEST(InspectRecordedRun, APeriodOfNinetyNineYearsIsThatGap) {
  testing::TempDir dir;
  constexpr std::int64_t kGapNs = 99LL * 365 * 86400 * 1'000'000'000;
  {
    auto store = storage::RunStore::create(dir / "run", {0, "slow", 0, {}, "", storage::RunStatus::kRunning, 1.0, {}},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    const storage::Sample samples[] = {{channel, 0, {}, 20.0, {}, storage::SampleStatus::kOk},
                                       {channel, kGapNs, {}, 20.0, {}, storage::SampleStatus::kOk}};
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, kGapNs);
  }
  const RecordedRun run = inspect_recorded_run(dir / "run");
  ASSERT_EQ(run.devices.size(), 1u);
  EXPECT_EQ(run.devices[0].period.count(), kGapNs);
  const auto config = acquisition::parse_experiment(replay_experiment_toml(run, {5020}, 10.0), "replay.toml");
  ASSERT_EQ(config.modbus_devices.size(), 1u);
  EXPECT_EQ(config.modbus_devices[0].poll_period,
            std::chrono::nanoseconds(std::llround(acquisition::TomlReader::kLongestSeconds * 1e9)));
}

// A recorded run: one device, `samples` ok samples of tc0 and tc1 150 ms
// apart from 1 s after its start at 1e18 ns.
void recorded_run(const std::filesystem::path& dir, int samples) {
  auto store = storage::RunStore::create(
      dir, {0, "recorded", 1'000'000'000'000'000'000, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
      storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
  for (const char* name : {"tc0", "tc1"}) {
    const auto channel = store.add_channel({0, device, name, "thermocouple", "degC", "K", {}, {}});
    std::vector<storage::Sample> series;
    for (int i = 0; i < samples; ++i) {
      series.push_back({channel, 1'000'000'001'000'000'000 + 150'000'000LL * i, {}, 20.0 + i, {},
                        storage::SampleStatus::kOk});
    }
    store.write_samples(series);
  }
  store.finish(storage::RunStatus::kComplete, 1'000'000'010'000'000'000);
}

// The replayed samples, polled late and unevenly, are stamped with the
// recorded times divided by the speed; a failed poll keeps its time, and a
// channel with more samples than recorded keeps all its times and is named.
TEST(StampFromRecording, SamplesTakeTheRecordedTimesScaledAndWhatCannotMatchIsNamed) {
  testing::TempDir dir;
  recorded_run(dir / "recorded", 4);
  const RecordedRun recorded = inspect_recorded_run(dir / "recorded");
  const std::int64_t started = 2'000'000'000'000'000'000;
  {
    auto store = storage::RunStore::create(
        dir / "replay", {0, "replay", started, {}, "", storage::RunStatus::kRunning, 2.0, std::nullopt},
        storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "generic", "127.0.0.1:1"});
    const auto tc0 = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    const auto tc1 = store.add_channel({0, device, "tc1", "thermocouple", "degC", "K", {}, {}});
    std::vector<storage::Sample> samples;
    const std::int64_t late_ns[] = {0, 9'000'000, 31'000'000, 2'000'000};  // each poll's lateness
    for (int i = 0; i < 4; ++i) {
      const std::int64_t t = started + 500'000'000 + 75'000'000LL * i + late_ns[i];
      samples.push_back({tc0, t, {}, 20.0 + i, {}, storage::SampleStatus::kOk});
      samples.push_back({tc1, t, {}, 20.0 + i, {}, storage::SampleStatus::kOk});
    }
    samples.push_back({tc1, started + 400'000'000, {}, {}, {}, storage::SampleStatus::kTimeout});  // drew nothing
    samples.push_back({tc1, started + 900'000'000, {}, 24.0, {}, storage::SampleStatus::kOk});     // one too many
    store.write_samples(samples);
    store.finish(storage::RunStatus::kComplete, started + 1'000'000'000);
  }
  const RecordingTimes times = stamp_from_recording(recorded, dir / "replay", started, 2.0);
  EXPECT_EQ(times.samples, 4u) << "tc0's four";
  EXPECT_EQ(times.frames, 0u);
  EXPECT_NEAR(times.largest_move_s, 0.031, 1e-9);
  ASSERT_EQ(times.problems.size(), 1u);
  EXPECT_NE(times.problems[0].find("adam/tc1: 5 samples replayed for 4 recorded"), std::string::npos)
      << times.problems[0];
  const auto replay = storage::RunStore::open(dir / "replay");
  const auto channels = replay.channels();
  const auto tc0 = replay.read_samples(channels[0].id);
  ASSERT_EQ(tc0.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(tc0[i].t_ns, started + 500'000'000 + 75'000'000LL * i) << i;
  const auto tc1 = replay.read_samples(channels[1].id);
  ASSERT_EQ(tc1.size(), 6u);
  EXPECT_EQ(tc1[0].t_ns, started + 400'000'000) << "tc1 is left as polled";
  EXPECT_EQ(tc1[2].t_ns, started + 500'000'000 + 75'000'000 + 9'000'000);
}

}  // namespace
}  // namespace bosfuse::sim
