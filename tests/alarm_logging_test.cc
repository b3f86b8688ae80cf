// Alarms through the real path: a simulated module on loopback read by the
// logger, with alarm limits from the experiment file. What a channel's
// limits see ends up as "alarm" / "alarm-cleared" events in the run (where
// the live page reads them) and as lines to the logger's on_alarm callback
// (what `acquire` prints), and the limits read back from the run's stored
// experiment file.

#include <gtest/gtest.h>

#include <future>
#include <mutex>

#include "tests/support/modbus_fixture.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace testing;

// Lines the logger's devices give on_alarm, from their threads.
class AlarmLines {
 public:
  std::function<void(const std::string&)> callback() {
    return [this](const std::string& line) {
      std::lock_guard lock(mutex_);
      lines_.push_back(line);
    };
  }
  std::vector<std::string> taken() {
    std::lock_guard lock(mutex_);
    return lines_;
  }

 private:
  std::mutex mutex_;
  std::vector<std::string> lines_;
};

// A module with tc0 watched by `alarm_keys` and tc1 not watched.
std::string module_toml(int port, const std::string& alarm_keys) {
  return tcp_device_toml("adam", port, 0, 0.05) + "[[devices.channels]]\nname = \"tc0\"\ninput = 0\n" + alarm_keys +
         "[[devices.channels]]\nname = \"tc1\"\ninput = 1\n";
}

std::vector<storage::Event> alarm_events(const storage::RunStore& store) {
  std::vector<storage::Event> out;
  for (const auto& e : store.events()) {
    if (e.kind == "alarm" || e.kind == "alarm-cleared") out.push_back(e);
  }
  return out;
}

bool starts_with(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The module serves a cooling curve from 85 °C: above a 40 °C limit all the
// run long, so one alarm is raised and never cleared.
TEST(AlarmLogging, AServedValueAboveTheLimitIsOneAlarmEventAndOneLine) {
  TempDir dir;
  sim::ModbusSimServer server(module_options("adam-6018", 2, loopback_tcp()));
  server.start();
  const std::string toml = module_toml(server.port(), "alarm_high = 40\n");
  const auto config = acquisition::parse_experiment(toml, "alarms.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  AlarmLines lines;
  const auto summary = log_for(store, config, 1500ms, {}, lines.callback());
  server.stop();

  ASSERT_GE(summary.devices.at(0).stats.polls_ok, 10) << summary.BriefReport();
  const auto alarms = alarm_events(store);
  ASSERT_EQ(alarms.size(), 1u) << "raised once, however many polls were above the limit";
  const storage::Event& alarm = alarms[0];
  EXPECT_EQ(alarm.kind, "alarm");
  EXPECT_EQ(alarm.device_id, device_id(store, "adam"));
  EXPECT_TRUE(starts_with(alarm.message, "tc0: high ")) << alarm.message;
  EXPECT_TRUE(ends_with(alarm.message, " degC above the limit 40 degC")) << alarm.message;
  // The value named is the first one logged, as stored.
  const double named = std::stod(alarm.message.substr(std::string("tc0: high ").size()));
  const auto first = samples_by_channel(store).at("tc0").at(0);
  ASSERT_TRUE(first.value.has_value());
  EXPECT_NEAR(named, *first.value, 0.05);
  EXPECT_GE(alarm.t_ns, first.t_ns);

  EXPECT_EQ(lines.taken(), std::vector<std::string>{"adam: " + alarm.message});

  // What the live page shows: the limits, read back from the run itself.
  const auto listed = acquisition::alarm_limits(acquisition::parse_experiment(store.run().config_toml, "run"));
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].device, "adam");
  EXPECT_EQ(listed[0].channel, "tc0");
  EXPECT_EQ(listed[0].unit, "degC");
  EXPECT_EQ(listed[0].limits.high, 40.0);
}

// The module stops answering (its port closes): tc0 goes stale while the
// logger retries, and the alarm clears when the module is back.
TEST(AlarmLogging, AChannelGoesStaleWhenItsModuleStopsAndClearsWhenItReturns) {
  TempDir dir;
  auto server = std::make_unique<sim::ModbusSimServer>(module_options("adam-6018", 2, loopback_tcp()));
  server->start();
  const int port = server->port();
  const std::string toml = module_toml(port, "alarm_stale_s = 0.5\n");
  const auto config = acquisition::parse_experiment(toml, "alarms.toml");
  auto store = storage::RunStore::create(dir / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  AlarmLines lines;
  auto run = std::async(std::launch::async, [&] { return log_for(store, config, 3500ms, {}, lines.callback()); });

  std::this_thread::sleep_for(700ms);
  const std::int64_t stopped_ns = acquisition::utc_now_ns();
  server.reset();
  std::this_thread::sleep_for(1500ms);
  const std::int64_t restarted_ns = acquisition::utc_now_ns();
  server = std::make_unique<sim::ModbusSimServer>(module_options("adam-6018", 2, loopback_tcp(port)));
  server->start();
  const auto summary = run.get();

  const auto alarms = alarm_events(store);
  ASSERT_EQ(alarms.size(), 2u) << summary.BriefReport();
  const storage::Event& stale = alarms[0];
  EXPECT_EQ(stale.kind, "alarm");
  EXPECT_EQ(stale.device_id, device_id(store, "adam"));
  EXPECT_TRUE(starts_with(stale.message, "tc0: stale no value for ")) << stale.message;
  EXPECT_TRUE(ends_with(stale.message, " s (limit 0.5 s)")) << stale.message;
  EXPECT_GT(stale.t_ns, stopped_ns + 400'000'000) << "stale before the limit had passed";
  EXPECT_LT(stale.t_ns, restarted_ns) << "not raised while the module was away";
  const storage::Event& cleared = alarms[1];
  EXPECT_EQ(cleared.kind, "alarm-cleared");
  EXPECT_TRUE(starts_with(cleared.message, "tc0: stale cleared at ")) << cleared.message;
  EXPECT_GT(cleared.t_ns, restarted_ns);

  EXPECT_EQ(lines.taken(), (std::vector<std::string>{"adam: " + stale.message, "adam: " + cleared.message}));
}

}  // namespace
}  // namespace bosfuse
