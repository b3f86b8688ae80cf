// What the logger does when devices misbehave: an unreachable device is
// reported and retried while the others are logged; a device that dies and
// comes back is recorded as a disconnect and a reconnect; a silent device
// yields timeout samples; burnout and out-of-range codes are stored with
// their status, never as temperatures.

#include <gtest/gtest.h>

#include <algorithm>
#include <future>

#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace testing;
using storage::SampleStatus;

std::int64_t count(const std::vector<std::string>& kinds, const std::string& kind) {
  return std::count(kinds.begin(), kinds.end(), kind);
}

TEST(ModbusFaults, UnreachableDeviceIsReportedRetriedAndOthersGoOn) {
  TempDir dir;
  sim::ModbusSimServer alive(module_options("adam-6018", 2, loopback_tcp()));
  alive.start();
  const std::string toml =
      tcp_device_toml("alive", alive.port(), 2, 0.05) + tcp_device_toml("dead", unused_loopback_port(), 2, 0.05);
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  const auto summary = log_for(store, config, 1500ms);

  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
  const auto& dead = summary.devices.at(1);
  EXPECT_EQ(dead.name, "dead");
  EXPECT_GE(dead.stats.connect_failures, 3) << "the dead device was not retried";
  EXPECT_EQ(count(event_kinds(store, device_id(store, "dead")), "error"), 1)
      << "one report per outage, not one per retry";
  EXPECT_GE(summary.devices.at(0).stats.polls_ok, 20) << "the dead device stalled the live one";
  const auto device_samples = [&](const std::string& device) {
    std::size_t n = 0;
    for (const auto& channel : store.channels()) {
      if (channel.device_id == device_id(store, device)) n += store.read_samples(channel.id).size();
    }
    return n;
  };
  EXPECT_GE(device_samples("alive"), 40u);
  EXPECT_EQ(device_samples("dead"), 0u) << "a device never reached has no readings to store";
}

TEST(ModbusFaults, DeviceThatDiesAndReturnsIsReconnected) {
  TempDir dir;
  auto server = std::make_unique<sim::ModbusSimServer>(module_options("adam-6018", 1, loopback_tcp()));
  server->start();
  const int port = server->port();
  const std::string toml = tcp_device_toml("adam", port, 1, 0.05);
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  auto run = std::async(std::launch::async, [&] { return log_for(store, config, 3s); });

  std::this_thread::sleep_for(700ms);
  server.reset();  // unplugged: the connection drops and the port closes
  std::this_thread::sleep_for(700ms);
  server = std::make_unique<sim::ModbusSimServer>(module_options("adam-6018", 1, loopback_tcp(port)));
  server->start();  // plugged back in on the same port
  const auto summary = run.get();

  const auto kinds = event_kinds(store, device_id(store, "adam"));
  EXPECT_EQ(count(kinds, "disconnect"), 1) << summary.BriefReport();
  EXPECT_EQ(count(kinds, "reconnect"), 1) << summary.BriefReport();
  EXPECT_EQ(summary.devices.at(0).stats.reconnects, 1);
  const auto samples = samples_by_channel(store).at("tc0");
  const auto timeouts =
      std::count_if(samples.begin(), samples.end(), [](const auto& s) { return s.status == SampleStatus::kTimeout; });
  EXPECT_GE(timeouts, 1) << "the failed poll left no trace";
  EXPECT_TRUE(samples.back().status == SampleStatus::kOk) << "logging did not resume";
  EXPECT_GE(server->served().size(), 10u) << "too little read after the reconnect";
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
}

TEST(ModbusFaults, SilentDeviceGivesTimeoutSamples) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 1, loopback_tcp()));
  server.start();
  server.set_silent(true);
  std::string toml = tcp_device_toml("adam", server.port(), 1, 0.1);
  toml.replace(toml.find("timeout_s = 0.5"), 15, "timeout_s = 0.1");
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  log_for(store, config, 1s);
  const auto samples = samples_by_channel(store).at("tc0");
  ASSERT_FALSE(samples.empty());
  for (const auto& s : samples) {
    EXPECT_EQ(s.status, SampleStatus::kTimeout);
    EXPECT_FALSE(s.value.has_value());
  }
  EXPECT_GE(count(event_kinds(store, device_id(store, "adam")), "disconnect"), 1);
}

TEST(ModbusFaults, BurnoutAndOutOfRangeAreStoredWithTheirStatus) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 3, loopback_tcp()));
  server.start();
  server.set_open_circuit(1, true);
  const std::string toml = tcp_device_toml("adam", server.port(), 3, 0.05) + "valid_range = [0.0, 50.0]\n";
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  std::vector<std::string> progress;
  log_for(store, config, 500ms, [&](const std::string& line) { progress.push_back(line); });
  ASSERT_FALSE(progress.empty());
  ASSERT_EQ(progress.back().substr(0, 10), "adam: tc0 ") << progress.back();
  EXPECT_NEAR(std::stod(progress.back().substr(10)), 80.0, 5.0) << "tc0 shows its latest temperature";
  EXPECT_NE(progress.back().find("tc1 open-circuit tc2 out-of-range"), std::string::npos) << progress.back();
  const auto samples = samples_by_channel(store);
  for (const auto& s : samples.at("tc1")) {
    EXPECT_EQ(s.status, SampleStatus::kOpenCircuit);
    EXPECT_FALSE(s.value.has_value()) << "a burnt-out thermocouple became a temperature";
    EXPECT_EQ(s.raw, 65535.0);
  }
  // tc2 serves ~85 degC but is configured valid only up to 50 degC.
  for (const auto& s : samples.at("tc2")) {
    EXPECT_EQ(s.status, SampleStatus::kOutOfRange);
    EXPECT_FALSE(s.value.has_value());
    ASSERT_TRUE(s.raw.has_value());
    EXPECT_GT(*s.raw * 1370.0 / 65535.0, 50.0) << "the raw reading is kept for diagnosis";
  }
  for (const auto& s : samples.at("tc0")) EXPECT_EQ(s.status, SampleStatus::kOk);
}

TEST(ModbusFaults, IcpdasUnderRangeCodeIsOutOfRange) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("icpdas-m7018", 1, loopback_tcp()));
  server.start();
  server.set_raw_override(0, -32768);
  acquisition::ModbusDeviceConfig device;
  device.name = "m7018";
  device.profile = "icpdas-m7018";
  device.endpoint = loopback_tcp(server.port());
  device.poll_period = 50ms;
  device.channels = sim::module_channels("icpdas-m7018", 1, "K");
  acquisition::ExperimentConfig config;
  config.modbus_devices.push_back(device);
  auto store = storage::RunStore::create(dir / "run", run_info(""), storage::RunStore::CreateMode::kNew);
  log_for(store, config, 400ms);
  const auto samples = samples_by_channel(store);
  ASSERT_FALSE(samples.at("tc0").empty());
  for (const auto& s : samples.at("tc0")) EXPECT_EQ(s.status, SampleStatus::kOutOfRange);
  for (const auto& s : samples.at("cold-junction")) EXPECT_EQ(s.status, SampleStatus::kOk);
}

}  // namespace
}  // namespace bosfuse
