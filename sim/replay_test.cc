#include "sim/replay.h"

#include <gtest/gtest.h>

#include "acquisition/experiment_config.h"

namespace bosfuse::sim {
namespace {

// Names a run store may hold: control characters, tab, newline, quotes,
// backslashes, TOML syntax and non-ASCII.
const std::vector<std::string> kAwkwardNames = {
    "tc\x01one", "tab\there", "line\nbreak", "say \"hi\"", "back\\slash\\", "Ofen 1 – Δ°C µ", "]] [x]\nname = \"y\"",
    "'single' ''' \"\"\"", "trailing\\"};

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

}  // namespace
}  // namespace bosfuse::sim
