// What the logger does when devices misbehave: an unreachable device is
// reported and retried while the others are logged; a device that dies and
// comes back is recorded as a disconnect and a reconnect; a silent device
// yields timeout samples; burnout and out-of-range codes are stored with
// their status, never as temperatures. A device that answers with a Modbus
// exception or a malformed frame (wrong transaction id, byte count or
// function code) yields bad-reply samples, with the exception code as raw;
// every outage is one event, however many polls it spans, and the polls
// during it back off, while a healthy device beside it keeps its schedule.

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
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
      tcp_device_toml("alive", alive.port(), 2, 0.05) + tcp_device_toml("dead", unused_loopback_port(), 2, 0.05, "d");
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
  EXPECT_EQ(count(event_kinds(store, device_id(store, "adam")), "disconnect"), 1) << "one event per outage";
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

// The samples of every channel of `device`, in time order per channel.
std::vector<storage::Sample> device_samples(const storage::RunStore& store, const std::string& device) {
  std::vector<storage::Sample> samples;
  for (const auto& channel : store.channels()) {
    if (channel.device_id != device_id(store, device)) continue;
    const auto more = store.read_samples(channel.id);
    samples.insert(samples.end(), more.begin(), more.end());
  }
  return samples;
}

std::string with_timeout(std::string toml, const std::string& timeout_s) {
  return toml.replace(toml.find("timeout_s = 0.5"), 15, "timeout_s = " + timeout_s);
}

constexpr double kPeriodS = 0.05;

// A fault the simulated module can be put into and taken out of, and what
// the logger must make of it.
struct FaultClass {
  std::string name;
  std::function<void(sim::ModbusSimServer&)> begin;
  std::function<void(sim::ModbusSimServer&)> end;
  SampleStatus status;
  std::optional<double> raw;
  std::string outage_event;    // the one event an outage records
  std::string recovery_event;  // and the one its end records
};

// Test listings show the fault's name, not the struct's bytes.
void PrintTo(const FaultClass& fault, std::ostream* out) { *out << fault.name; }

std::vector<FaultClass> fault_classes() {
  using Malformed = sim::ModbusSimServer::MalformedReply;
  const auto exception = [](int code) {
    return FaultClass{"Exception" + std::to_string(code),
                      [code](sim::ModbusSimServer& s) { s.set_exception_reply(code); },
                      [](sim::ModbusSimServer& s) { s.set_exception_reply(std::nullopt); },
                      SampleStatus::kBadReply,
                      code,
                      "bad-reply",
                      "recovered"};
  };
  const auto malformed = [](std::string name, Malformed kind) {
    return FaultClass{std::move(name),
                      [kind](sim::ModbusSimServer& s) { s.set_malformed_reply(kind); },
                      [](sim::ModbusSimServer& s) { s.set_malformed_reply(Malformed::kNone); },
                      SampleStatus::kBadReply,
                      std::nullopt,
                      "bad-reply",
                      "recovered"};
  };
  return {
      exception(2),  // illegal data address
      exception(4),  // server failure
      malformed("WrongTransactionId", Malformed::kWrongTransactionId),
      malformed("WrongByteCount", Malformed::kWrongByteCount),
      malformed("WrongFunctionCode", Malformed::kWrongFunctionCode),
      {"Silence", [](sim::ModbusSimServer& s) { s.set_silent(true); },
       [](sim::ModbusSimServer& s) { s.set_silent(false); }, SampleStatus::kTimeout, std::nullopt, "disconnect", "reconnect"},
      {"SlowReplies", [](sim::ModbusSimServer& s) { s.set_reply_delay(600ms); },
       [](sim::ModbusSimServer& s) { s.set_reply_delay(0ms); }, SampleStatus::kTimeout, std::nullopt, "disconnect",
       "reconnect"},
  };
}

class FaultyBesideHealthy : public ::testing::TestWithParam<FaultClass> {};

// One outage of about a second in the middle of a 2.5 s run, with a healthy
// device polled beside the faulty one at the same 20 Hz.
TEST_P(FaultyBesideHealthy, RightStatusOneEventPerOutageAndTheHealthyOneUndisturbed) {
  const FaultClass& fault = GetParam();
  TempDir dir;
  sim::ModbusSimServer healthy(module_options("adam-6018", 2, loopback_tcp()));
  sim::ModbusSimServer faulty(module_options("adam-6018", 2, loopback_tcp()));
  healthy.start();
  faulty.start();
  const std::string toml = tcp_device_toml("healthy", healthy.port(), 2, kPeriodS) +
                           with_timeout(tcp_device_toml("faulty", faulty.port(), 2, kPeriodS, "f"), "0.2");
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  auto run = std::async(std::launch::async, [&] { return log_for(store, config, 2500ms); });
  std::this_thread::sleep_for(500ms);
  fault.begin(faulty);
  std::this_thread::sleep_for(1000ms);
  fault.end(faulty);
  const auto summary = run.get();
  ASSERT_EQ(summary.devices.at(1).name, "faulty");

  const auto samples = device_samples(store, "faulty");
  const auto failed = std::count_if(samples.begin(), samples.end(), [](const auto& s) { return s.status != SampleStatus::kOk; });
  EXPECT_GE(failed, 2) << "the outage left no trace";
  for (const auto& s : samples) {
    if (s.status == SampleStatus::kOk) continue;
    EXPECT_EQ(s.status, fault.status) << storage::to_string(s.status);
    EXPECT_EQ(s.raw, fault.raw);
    EXPECT_FALSE(s.value.has_value());
  }
  EXPECT_EQ(samples.back().status, SampleStatus::kOk) << "logging did not resume after the outage";

  const auto kinds = event_kinds(store, device_id(store, "faulty"));
  EXPECT_EQ(count(kinds, fault.outage_event), 1) << summary.BriefReport();
  EXPECT_EQ(count(kinds, fault.recovery_event), 1) << "one recovery per outage\n" << summary.BriefReport();
  EXPECT_EQ(kinds.size(), 3u) << "connect, one outage, one recovery\n" << summary.BriefReport();
  EXPECT_EQ(summary.devices.at(1).stats.reconnects, 1);
  // 20 polls fit in the outage; backing off (50 ms doubling to 200 ms here)
  // leaves well under half of them.
  EXPECT_LE(summary.devices.at(1).stats.polls_failed, 9) << summary.BriefReport();

  const auto& well = summary.devices.at(0);
  EXPECT_GE(static_cast<double>(well.stats.polls_ok), 0.9 * summary.elapsed_s / kPeriodS) << summary.BriefReport();
  for (const auto& s : device_samples(store, "healthy")) EXPECT_EQ(s.status, SampleStatus::kOk);
  EXPECT_TRUE(event_kinds(store, device_id(store, "healthy")) == std::vector<std::string>{"connect"})
      << summary.BriefReport();
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
}

INSTANTIATE_TEST_SUITE_P(ModbusFaults, FaultyBesideHealthy, ::testing::ValuesIn(fault_classes()),
                         [](const auto& info) { return info.param.name; });

TEST(ModbusFaults, ExceptionFromTheFirstPollIsOneOutageOfBadReplies) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 2, loopback_tcp()));
  server.start();
  server.set_exception_reply(2);
  const std::string toml = tcp_device_toml("adam", server.port(), 2, kPeriodS);
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  const auto summary = log_for(store, config, 1500ms);

  const auto samples = device_samples(store, "adam");
  ASSERT_FALSE(samples.empty());
  for (const auto& s : samples) {
    EXPECT_EQ(s.status, SampleStatus::kBadReply);
    EXPECT_EQ(s.raw, 2.0) << "the exception code is kept for diagnosis";
  }
  const auto kinds = event_kinds(store, device_id(store, "adam"));
  EXPECT_EQ(count(kinds, "bad-reply"), 1) << summary.BriefReport();
  EXPECT_EQ(count(kinds, "disconnect"), 0) << summary.BriefReport();
  EXPECT_EQ(summary.devices.at(0).stats.reconnects, 0) << "the link was never lost";
  EXPECT_LE(summary.devices.at(0).stats.polls_failed, 12) << "no backoff: " << summary.BriefReport();
}

// Debounce with a real Modbus module: one failing every other request (a
// loose contact) is one outage, a bad-reply event when it starts and one
// recovered event, saying how many polls failed, once it has answered
// three polls in a row; every failed poll is still a bad-reply sample.
TEST(ModbusFaults, AModuleFailingEveryOtherPollIsOneOutage) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 2, loopback_tcp()));
  server.start();
  const std::string toml = tcp_device_toml("adam", server.port(), 2, kPeriodS);
  const auto config = acquisition::parse_experiment(toml, "faults.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  auto run = std::async(std::launch::async, [&] { return log_for(store, config, 2000ms); });
  std::this_thread::sleep_for(300ms);
  server.set_exception_every_other(4);
  std::this_thread::sleep_for(1000ms);
  server.set_exception_every_other(std::nullopt);
  const auto summary = run.get();

  const auto samples = samples_by_channel(store).at("tc0");
  int failures_after_success = 0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].status == SampleStatus::kBadReply && samples[i - 1].status == SampleStatus::kOk) {
      ++failures_after_success;
    }
  }
  EXPECT_GE(failures_after_success, 4) << "the module did not fail every other poll\n" << summary.BriefReport();
  EXPECT_EQ(samples.back().status, SampleStatus::kOk);
  EXPECT_EQ(event_kinds(store, device_id(store, "adam")),
            (std::vector<std::string>{"connect", "bad-reply", "recovered"}))
      << summary.BriefReport();
  const auto events = store.events();
  const auto recovered =
      std::find_if(events.begin(), events.end(), [](const auto& e) { return e.kind == "recovered"; });
  ASSERT_NE(recovered, events.end());
  EXPECT_NE(recovered->message.find(std::to_string(summary.devices.at(0).stats.polls_failed) + " failed polls"),
            std::string::npos)
      << recovered->message;
  EXPECT_EQ(summary.devices.at(0).stats.reconnects, 1);
}

}  // namespace
}  // namespace bosfuse
