// End-to-end Modbus logging: the logger reads a simulated module (a real
// libmodbus server) over loopback TCP and over RTU through a socat
// pseudo-terminal pair, and every value served must land in the run store,
// in order, with increasing timestamps.

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <map>

#include "acquisition/clock.h"
#include "acquisition/config/experiment_config.h"
#include "acquisition/logger.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace testing;

using acquisition::ModbusEndpoint;
using acquisition::ModbusTransport;
using storage::SampleStatus;
using namespace std::chrono_literals;

// Every value the module served reached the store, in order, nothing more.
void expect_served_values_stored(const sim::ModbusSimServer& server,
                                 const std::vector<acquisition::ModbusChannel>& channels,
                                 const storage::RunStore& store) {
  const auto stored = samples_by_channel(store);
  std::vector<std::vector<sim::ModbusSimServer::ServedValue>> served(channels.size());
  for (const auto& s : server.served()) served[static_cast<std::size_t>(s.channel)].push_back(s);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const auto& samples = stored.at(channels[c].name);
    SCOPED_TRACE(channels[c].name);
    ASSERT_GE(served[c].size(), 5u) << "too few polls to mean anything";
    ASSERT_EQ(samples.size(), served[c].size());
    for (std::size_t i = 0; i < samples.size(); ++i) {
      ASSERT_EQ(samples[i].status, SampleStatus::kOk);
      ASSERT_EQ(samples[i].value, served[c][i].reading.value) << "sample " << i;
      ASSERT_EQ(samples[i].raw, served[c][i].reading.raw) << "sample " << i;
      if (i > 0) {
        ASSERT_GT(samples[i].t_ns, samples[i - 1].t_ns) << "sample " << i;
      }
      // Stamped at the midpoint of request and reply: within a second of
      // the moment the server produced the value.
      ASSERT_LT(std::llabs(samples[i].t_ns - served[c][i].t_ns), 1'000'000'000LL);
    }
  }
}

TEST(ModbusLogging, EveryValueServedOverTcpLandsInOrder) {
  testing::TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 4, loopback_tcp()));
  server.start();
  const std::string toml = "[run]\nname = \"tcp\"\n" + tcp_device_toml("adam", server.port(), 4, 0.05);
  const auto config = acquisition::parse_experiment(toml, "tcp.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  const auto summary = log_for(store, config, 2s);
  server.stop();
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
  EXPECT_EQ(store.run().config_toml, toml);
  EXPECT_EQ(summary.devices.at(0).stats.polls_failed, 0);
  expect_served_values_stored(server, config.modbus_devices[0].channels, store);
  // 2 s at 20 Hz: the fixed schedule delivers close to 40 polls.
  EXPECT_GE(summary.devices.at(0).stats.polls_ok, 30);
  EXPECT_LE(summary.devices.at(0).stats.polls_ok, 42);
}

TEST(ModbusLogging, EveryValueServedOverRtuThroughAPseudoTerminalLandsInOrder) {
  testing::TempDir dir;
  const std::string server_end = (dir / "module").string();
  const std::string logger_end = (dir / "logger").string();
  testing::BackgroundProcess socat({"socat", "pty,raw,echo=0,link=" + server_end, "pty,raw,echo=0,link=" + logger_end});
  ASSERT_TRUE(
      testing::wait_for([&] { return std::filesystem::exists(server_end) && std::filesystem::exists(logger_end); }, 5s))
      << "socat did not create the pseudo-terminal pair";

  ModbusEndpoint endpoint;
  endpoint.transport = ModbusTransport::kRtu;
  endpoint.serial_port = server_end;
  endpoint.baud = 115200;
  endpoint.unit_id = 3;
  sim::ModbusSimServer server(module_options("icpdas-m7018", 3, endpoint));
  server.start();

  acquisition::ModbusDeviceConfig device;
  device.name = "m7018";
  device.profile = "icpdas-m7018";
  device.endpoint = endpoint;
  device.endpoint.serial_port = logger_end;
  device.poll_period = 100ms;
  device.channels = sim::module_channels("icpdas-m7018", 3, "K");
  acquisition::ExperimentConfig config;
  config.modbus_devices.push_back(device);

  auto store = storage::RunStore::create(dir / "run", run_info(""), storage::RunStore::CreateMode::kNew);
  const auto summary = log_for(store, config, 2s);
  server.stop();
  EXPECT_EQ(summary.devices.at(0).stats.polls_failed, 0) << summary.BriefReport();
  expect_served_values_stored(server, device.channels, store);
  const auto stored = samples_by_channel(store);
  EXPECT_NEAR(*stored.at("cold-junction").front().value, 22.0, 2.0) << "cold junction reads ambient";
}

}  // namespace
}  // namespace bosfuse
