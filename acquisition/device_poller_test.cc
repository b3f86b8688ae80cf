// The poller's logic against a scripted source: schedule, statuses,
// reconnection. The real Modbus path is tested in tests/.

#include "acquisition/device_poller.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <thread>

#include "tests/support/temp_dir.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;
using storage::SampleStatus;

// A source whose behaviour the test scripts: how long a read takes, how
// many connection attempts fail, which reads fail.
class ScriptedSource : public ThermocoupleSource {
 public:
  std::chrono::milliseconds read_time{0};
  std::atomic<int> connect_failures_left{0};
  std::atomic<int> reads_failing_from{-1};  // read index from which reads fail
  std::atomic<int> reads_failing_count{0};
  std::atomic<int> reads{0};
  std::atomic<int> connects{0};

  storage::DeviceInfo device_info() const override { return {0, "scripted", "test", "", "nowhere"}; }
  std::vector<storage::ChannelInfo> channel_infos() const override {
    return {{0, 0, "a", "thermocouple", "degC", "K", {}, {}}, {0, 0, "b", "thermocouple", "degC", "K", {}, {}}};
  }
  void connect() override {
    ++connects;
    if (connect_failures_left.load() > 0) {
      --connect_failures_left;
      throw DeviceError("refused");
    }
  }
  void disconnect() override {}
  std::vector<std::string> take_notices() override {
    std::lock_guard lock(notices_mutex);
    return std::exchange(notices, {});
  }
  std::mutex notices_mutex;
  std::vector<std::string> notices;
  std::vector<ChannelReading> read() override {
    const int index = reads++;
    std::this_thread::sleep_for(read_time);
    const int from = reads_failing_from.load();
    if (from >= 0 && index >= from && index < from + reads_failing_count.load()) throw DeviceError("no reply");
    return {{double(index), double(index), SampleStatus::kOk}, {std::nullopt, 65535, SampleStatus::kOpenCircuit}};
  }
};

struct Harness {
  testing::TempDir dir;
  storage::RunStore store = storage::RunStore::create(dir / "run", {0, "t", 0, {}, "", storage::RunStatus::kRunning},
                                                      storage::RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "scripted", "test", "", ""});
  std::vector<std::int64_t> channels = {store.add_channel({0, device, "a", "thermocouple", "degC", "K", {}, {}}),
                                        store.add_channel({0, device, "b", "thermocouple", "degC", "K", {}, {}})};

  DevicePoller::Stats run(std::unique_ptr<ScriptedSource> source, DevicePoller::Options options,
                          std::chrono::milliseconds duration) {
    storage::RunWriter writer(store, {20ms, 10'000});
    DevicePoller poller(std::move(source), device, channels, writer, options);
    poller.start();
    std::this_thread::sleep_for(duration);
    poller.stop();
    writer.flush();
    return poller.stats();
  }
  std::vector<std::string> event_kinds() const {
    std::vector<std::string> kinds;
    for (const auto& e : store.events()) kinds.push_back(e.kind);
    return kinds;
  }
};

TEST(DevicePoller, FixedScheduleDoesNotDriftWhenReadsTakeTime) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->read_time = 4ms;  // a drifting "sleep one period after each poll" loop would lose 4 ms per poll
  const auto stats = h.run(std::move(source), {20ms, 250ms, 10s, {}}, 2050ms);
  const auto samples = h.store.read_samples(h.channels[0]);
  ASSERT_GE(samples.size(), 90u);
  // 100 polls due in 2.05 s; drift would have cost 100 × 4 ms = 0.4 s, i.e. ~17 polls.
  EXPECT_GE(stats.polls_ok, 98) << "the schedule drifted";
  EXPECT_LE(stats.polls_ok, 104);
  const double span_s = static_cast<double>(samples.back().t_ns - samples.front().t_ns) * 1e-9;
  EXPECT_NEAR(span_s, 0.020 * static_cast<double>(samples.size() - 1), 0.06);
}

TEST(DevicePoller, StatusesPassThroughAndOpenCircuitHasNoValue) {
  Harness h;
  h.run(std::make_unique<ScriptedSource>(), {50ms, 250ms, 10s, {}}, 300ms);
  for (const auto& s : h.store.read_samples(h.channels[1])) {
    EXPECT_EQ(s.status, SampleStatus::kOpenCircuit);
    EXPECT_FALSE(s.value.has_value());
    EXPECT_EQ(s.raw, 65535);
  }
  EXPECT_FALSE(h.store.read_samples(h.channels[0]).empty());
}

TEST(DevicePoller, UnreachableDeviceIsReportedOnceAndRetriedWithBackoff) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->connect_failures_left = 4;
  ScriptedSource* probe = source.get();
  const auto stats = h.run(std::move(source), {20ms, 20ms, 80ms, {}}, 800ms);
  // Backoff 20, 40, 80, 80 ms: connected after ~220 ms, then polled.
  EXPECT_EQ(stats.connect_failures, 4);
  EXPECT_EQ(probe->connects.load(), 5);
  EXPECT_GE(stats.polls_ok, 15);
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"error", "connect"}));
  EXPECT_NE(h.store.events()[1].message.find("connected after"), std::string::npos);
}

TEST(DevicePoller, FailedReadsBecomeTimeoutSamplesThenReconnect) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->reads_failing_from = 5;
  source->reads_failing_count = 1;
  const auto stats = h.run(std::move(source), {20ms, 20ms, 80ms, {}}, 600ms);
  EXPECT_EQ(stats.polls_failed, 1);
  EXPECT_EQ(stats.reconnects, 1);
  const auto samples = h.store.read_samples(h.channels[0]);
  ASSERT_GT(samples.size(), 6u);
  EXPECT_EQ(samples[5].status, SampleStatus::kTimeout);
  EXPECT_FALSE(samples[5].value.has_value());
  EXPECT_EQ(samples[6].status, SampleStatus::kOk);
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "disconnect", "reconnect"}));
}

TEST(DevicePoller, StopsAfterItsPollCount) {
  Harness h;
  const auto stats = h.run(std::make_unique<ScriptedSource>(), {10ms, 250ms, 10s, 7}, 400ms);
  EXPECT_EQ(stats.polls_ok, 7);
  EXPECT_EQ(h.store.read_samples(h.channels[0]).size(), 7u);
  EXPECT_EQ(h.event_kinds().back(), "stopped");
}

TEST(DevicePoller, InvalidOptionsAreRefused) {
  Harness h;
  storage::RunWriter writer(h.store);
  EXPECT_THROW(DevicePoller(std::make_unique<ScriptedSource>(), h.device, h.channels, writer, {0ms, 20ms, 80ms, {}}),
               std::invalid_argument);
  EXPECT_THROW(DevicePoller(std::make_unique<ScriptedSource>(), h.device, {1}, writer, {20ms, 20ms, 80ms, {}}),
               std::invalid_argument);
}

TEST(DevicePoller, SourceNoticesBecomeHotplugEvents) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->notices = {"unplugged from bus 1 device 7", "plugged in at bus 1 device 8"};
  h.run(std::move(source), {20ms, 250ms, 10s, {}}, 200ms);
  std::vector<std::string> messages;
  for (const auto& e : h.store.events()) {
    if (e.kind == "hotplug") messages.push_back(e.message);
  }
  EXPECT_EQ(messages, (std::vector<std::string>{"unplugged from bus 1 device 7", "plugged in at bus 1 device 8"}));
}

}  // namespace
}  // namespace bosfuse::acquisition
