// The poller's logic against a scripted source: schedule, statuses,
// reconnection. The real Modbus path is tested in tests/.

#include "acquisition/device_poller.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <mutex>
#include <thread>

#include "tests/support/temp_dir.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;
using storage::SampleStatus;

// A source whose behaviour the test scripts: how long a read takes, how
// many connection attempts fail, which reads fail and how. Its counters are
// shared, so a test reads them after the poller (and the source) are gone.
class ScriptedSource : public ThermocoupleSource {
 public:
  struct Counters {
    std::atomic<int> reads{0};
    std::atomic<int> connects{0};
    std::atomic<int> disconnects{0};
  };
  std::chrono::milliseconds read_time{0};
  std::atomic<int> connect_failures_left{0};
  std::atomic<int> reads_failing_from{-1};  // read index from which reads fail
  std::atomic<int> reads_failing_count{0};
  std::atomic<int> alternating_until{0};  // reads before this index fail every other time (the odd ones)
  SampleStatus failure_status = SampleStatus::kTimeout;
  std::optional<double> failure_raw;
  bool throw_unexpected = false;  // the first failing read throws something that is no DeviceError
  std::shared_ptr<Counters> counters = std::make_shared<Counters>();

  storage::DeviceInfo device_info() const override { return {0, "scripted", "test", "", "nowhere"}; }
  std::vector<storage::ChannelInfo> channel_infos() const override {
    return {{0, 0, "a", "thermocouple", "degC", "K", {}, {}}, {0, 0, "b", "thermocouple", "degC", "K", {}, {}}};
  }
  void connect() override {
    ++counters->connects;
    if (connect_failures_left.load() > 0) {
      --connect_failures_left;
      throw DeviceError("refused");
    }
  }
  void disconnect() override { ++counters->disconnects; }
  std::vector<std::string> take_notices() override {
    std::lock_guard lock(notices_mutex);
    return std::exchange(notices, {});
  }
  std::mutex notices_mutex;
  std::vector<std::string> notices;
  std::vector<ChannelReading> read() override {
    const int index = counters->reads++;
    std::this_thread::sleep_for(read_time);
    const int from = reads_failing_from.load();
    const bool alternate_failure = index < alternating_until.load() && index % 2 == 1;
    if (alternate_failure || (from >= 0 && index >= from && index < from + reads_failing_count.load())) {
      if (throw_unexpected && index == from) throw std::out_of_range("a bug in a device driver");
      throw DeviceError(failure_status == SampleStatus::kBadReply ? "exception reply" : "no reply", failure_status,
                        failure_raw);
    }
    return {{double(index), double(index), SampleStatus::kOk}, {std::nullopt, 65535, SampleStatus::kOpenCircuit}};
  }
};

struct Harness {
  testing::TempDir dir;
  storage::RunStore store = storage::RunStore::create(dir / "run", {0, "t", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                                      storage::RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "scripted", "test", "", ""});
  std::vector<std::int64_t> channels = {store.add_channel({0, device, "a", "thermocouple", "degC", "K", {}, {}}),
                                        store.add_channel({0, device, "b", "thermocouple", "degC", "K", {}, {}})};

  DevicePoller::Stats run(std::unique_ptr<ScriptedSource> source, DevicePollerOptions options,
                          std::chrono::milliseconds duration) {
    storage::RunWriter writer(store, {20ms, 10'000});
    const auto poller = std::make_shared<DevicePoller>(std::move(source), device, channels, writer, options);
    poller->start();
    std::this_thread::sleep_for(duration);
    EXPECT_TRUE(poller->stop());
    writer.flush();
    return poller->stats();
  }
  // Without "skipped": a loaded machine can make any poller skip a poll;
  // the tests of skipped polls read those events themselves.
  std::vector<std::string> event_kinds() const {
    std::vector<std::string> kinds;
    for (const auto& e : store.events()) {
      if (e.kind != "skipped") kinds.push_back(e.kind);
    }
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
  // 100 polls due in 2.05 s; drift would have cost 100 × 4 ms = 0.4 s, i.e.
  // ~17 polls, never counted as skipped. A loaded machine (a sanitizer
  // build) may wake late and skip ticks of the grid, which are counted.
  EXPECT_GE(stats.polls_ok + stats.missed_ticks, 98) << "the schedule drifted";
  EXPECT_LE(stats.polls_ok + stats.missed_ticks, 104);
  // The samples sit on the 20 ms grid: their span is the ticks they cover,
  // polls plus the ticks a late wake-up skipped (a loaded machine), never
  // more, as a drifting loop's would be.
  const double span_s = static_cast<double>(samples.back().t_ns - samples.front().t_ns) * 1e-9;
  const double ticks = static_cast<double>(samples.size() - 1 + static_cast<std::size_t>(stats.missed_ticks));
  EXPECT_NEAR(span_s, 0.020 * ticks, 0.03) << stats.missed_ticks << " ticks skipped";
}

// What the run says about skipped polls: the "skipped" events' counts.
std::vector<std::int64_t> skipped_counts(const storage::RunStore& store,
                                         std::vector<std::int64_t>* times_ns = nullptr) {
  std::vector<std::int64_t> counts;
  for (const auto& e : store.events()) {
    if (e.kind != "skipped") continue;
    const auto space = e.message.find(' ');
    EXPECT_EQ(e.message.substr(space), " polls skipped (device too slow)") << e.message;
    EXPECT_TRUE(e.device_id.has_value());
    counts.push_back(std::stoll(e.message.substr(0, space)));
    if (times_ns) times_ns->push_back(e.t_ns);
  }
  return counts;
}

std::int64_t sum(const std::vector<std::int64_t>& counts) {
  std::int64_t total = 0;
  for (const std::int64_t n : counts) total += n;
  return total;
}

// Polls a device too slow for its period skipped are in the run, not only
// in this process's stats: reported at once, then at most once per
// interval (10 s here, longer than the run), the rest at the stop.
TEST(DevicePoller, PollsSkippedByASlowDeviceAreRecordedAsEvents) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->read_time = 50ms;  // a 20 ms period: two or three ticks missed per poll
  const auto stats = h.run(std::move(source), {20ms, 250ms, 10s, {}}, 500ms);
  ASSERT_GE(stats.missed_ticks, 10) << "the source was not too slow";
  const auto counts = skipped_counts(h.store);
  ASSERT_EQ(counts.size(), 2u) << "the first skips at once, the rest at the stop";
  EXPECT_EQ(sum(counts), stats.missed_ticks) << "the events do not add up to the polls skipped";
  EXPECT_EQ(h.store.events().back().kind, "skipped") << "the rest was not told at the stop";
}

TEST(DevicePoller, SkippedPollEventsAreSpacedByTheirInterval) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->read_time = 25ms;
  DevicePollerOptions options{10ms, 250ms, 10s, {}};
  options.skipped_event_interval = 200ms;
  const auto stats = h.run(std::move(source), options, 1100ms);
  std::vector<std::int64_t> times_ns;
  const auto counts = skipped_counts(h.store, &times_ns);
  EXPECT_EQ(sum(counts), stats.missed_ticks);
  ASSERT_GE(counts.size(), 3u);
  EXPECT_LE(counts.size(), 8u) << "one event per skipped poll, not per interval";
  for (std::size_t i = 1; i + 1 < times_ns.size(); ++i) {  // the last one is the stop's
    EXPECT_GE(times_ns[i] - times_ns[i - 1], 190'000'000) << "event " << i << " came too soon";
  }
  storage::RunWriter writer(h.store);
  options.skipped_event_interval = 0ms;
  EXPECT_THROW(DevicePoller(std::make_unique<ScriptedSource>(), h.device, h.channels, writer, options),
               std::invalid_argument);
}

// Lines given to on_alarm, from the poller's thread.
struct AlarmLines {
  std::mutex mutex;
  std::vector<std::string> lines;
  std::function<void(const std::string&)> callback() {
    return [this](const std::string& line) {
      std::lock_guard lock(mutex);
      lines.push_back(line);
    };
  }
  std::vector<std::string> taken() {
    std::lock_guard lock(mutex);
    return lines;
  }
};

std::vector<std::string> alarm_events(const storage::RunStore& store) {
  std::vector<std::string> out;
  for (const auto& e : store.events()) {
    if (e.kind == "alarm" || e.kind == "alarm-cleared") out.push_back(e.kind + " " + e.message);
  }
  return out;
}

// Channel a reads 0, 1, 2, ... (one more each poll); b is open-circuit.
TEST(DevicePoller, AlarmsAreRunEventsAndLinesToTheCallback) {
  Harness h;
  AlarmLines lines;
  DevicePollerOptions options{20ms, 250ms, 10s, {}};
  options.alarms = {AlarmLimits{{}, 5.0, {}, {}}, AlarmLimits{{}, {}, {}, 0.2}};
  options.on_alarm = lines.callback();
  h.run(std::make_unique<ScriptedSource>(), options, 500ms);
  // In either order: a slow machine may delay the seventh poll past 0.2 s.
  auto alarms = alarm_events(h.store);
  std::sort(alarms.begin(), alarms.end());
  ASSERT_EQ(alarms.size(), 2u) << ::testing::PrintToString(alarms);
  EXPECT_EQ(alarms[0], "alarm a: high 6.0 degC above the limit 5 degC");
  EXPECT_THAT(alarms[1], ::testing::MatchesRegex(R"(alarm b: stale no value for 0\.[2-9] s \(limit 0\.2 s\))"));
  for (const auto& e : h.store.events()) EXPECT_EQ(e.device_id, h.device) << e.kind;
  auto lines_given = lines.taken();
  std::sort(lines_given.begin(), lines_given.end());
  ASSERT_EQ(lines_given.size(), 2u);
  EXPECT_EQ(lines_given[0], "scripted: a: high 6.0 degC above the limit 5 degC");
  EXPECT_EQ(lines_given[1], "scripted: " + alarms[1].substr(6));
}

// Stale is checked while the poller waits, not only when it polls: a device
// that cannot be reached, with 2 s between attempts, is stale on time.
TEST(DevicePoller, AChannelGoesStaleWhileItsDeviceCannotBeReached) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->connect_failures_left = 1000;
  AlarmLines lines;
  DevicePollerOptions options{20ms, 2s, 2s, {}};
  options.alarms = {AlarmLimits{{}, {}, {}, 0.3}, AlarmLimits{}};
  options.on_alarm = lines.callback();
  const auto stats = h.run(std::move(source), options, 1500ms);
  EXPECT_EQ(stats.connect_failures, 1) << "attempts were not 2 s apart";
  const auto alarms = alarm_events(h.store);
  ASSERT_EQ(alarms.size(), 1u) << ::testing::PrintToString(alarms);
  EXPECT_EQ(alarms[0].substr(0, 28), "alarm a: stale no value for ") << alarms[0];
  EXPECT_EQ(lines.taken().size(), 1u);
}

TEST(DevicePoller, AlarmLimitsMustFitTheChannels) {
  Harness h;
  storage::RunWriter writer(h.store);
  DevicePollerOptions options{20ms, 20ms, 80ms, {}};
  options.alarms = {AlarmLimits{{}, 5.0, {}, {}}};  // two channels
  EXPECT_THROW(DevicePoller(std::make_unique<ScriptedSource>(), h.device, h.channels, writer, options),
               std::invalid_argument);
  options.alarms = {AlarmLimits{{}, 5.0, {}, {}}, AlarmLimits{5.0, 1.0, {}, {}}};
  try {
    DevicePoller(std::make_unique<ScriptedSource>(), h.device, h.channels, writer, options);
    ADD_FAILURE() << "limits with low above high were taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "device scripted: channel b: alarm_high: must be above alarm_low (5)");
  }
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
  const auto counters = source->counters;
  const auto stats = h.run(std::move(source), {20ms, 20ms, 80ms, {}}, 800ms);
  // Backoff 20, 40, 80, 80 ms: connected after ~220 ms, then polled.
  EXPECT_EQ(stats.connect_failures, 4);
  EXPECT_EQ(counters->connects.load(), 5);
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

// A device that keeps failing is one outage: one event when it starts, one
// when it ends, attempts spaced by the backoff in between (not one pair of
// disconnect/reconnect events per poll).
TEST(DevicePoller, AnOutageIsRecordedOnceAndRetriedWithBackoff) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->reads_failing_from = 3;
  source->reads_failing_count = 6;
  const auto counters = source->counters;
  const auto stats = h.run(std::move(source), {10ms, 20ms, 80ms, {}}, 900ms);
  EXPECT_EQ(stats.polls_failed, 6);
  EXPECT_EQ(stats.reconnects, 1);
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "disconnect", "reconnect"}));
  // Backoff 20, 40, 80, 80, 80 ms between the six failed attempts: ~300 ms
  // for what a poll on every 10 ms tick would have spent 60 ms on.
  const auto samples = h.store.read_samples(h.channels[0]);
  ASSERT_GT(samples.size(), 10u);
  EXPECT_EQ(samples[3].status, SampleStatus::kTimeout);
  EXPECT_GE(samples[9].t_ns - samples[3].t_ns, 280'000'000) << "failed attempts were not spaced by the backoff";
  EXPECT_EQ(samples[9].status, SampleStatus::kOk);
}

// Debounce: a device that fails every other poll is one outage (two
// events), not a disconnect/reconnect pair per poll. It ends only after
// recovery_polls good polls in a row, saying how many polls failed, and
// every failed poll is still a sample with the failure's status.
TEST(DevicePoller, ADeviceFailingEveryOtherPollIsOneOutage) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->alternating_until = 20;  // reads 1, 3, ... 19 fail
  DevicePollerOptions options{10ms, 10ms, 80ms, 26};
  options.recovery_polls = 3;
  const auto stats = h.run(std::move(source), options, 1500ms);
  EXPECT_EQ(stats.polls_ok + stats.polls_failed, 26);
  EXPECT_EQ(stats.polls_failed, 10);
  EXPECT_EQ(stats.reconnects, 1);
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "disconnect", "reconnect", "stopped"}));
  const auto events = h.store.events();
  const auto reconnect =
      std::find_if(events.begin(), events.end(), [](const auto& e) { return e.kind == "reconnect"; });
  ASSERT_NE(reconnect, events.end());
  EXPECT_NE(reconnect->message.find("(10 failed polls)"), std::string::npos) << reconnect->message;
  const auto samples = h.store.read_samples(h.channels[0]);
  ASSERT_EQ(samples.size(), 26u);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const bool failed = i < 20 && i % 2 == 1;
    EXPECT_EQ(samples[i].status, failed ? SampleStatus::kTimeout : SampleStatus::kOk) << i;
  }
}

// Without the debounce (recovery_polls = 1) the same device is what the
// probe found: an event pair per failed poll.
TEST(DevicePoller, WithoutTheDebounceEveryFailedPollIsAnOutage) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->alternating_until = 20;
  DevicePollerOptions options{10ms, 10ms, 80ms, 26};
  options.recovery_polls = 1;
  h.run(std::move(source), options, 1500ms);
  const auto kinds = h.event_kinds();
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "disconnect"), 10);
  EXPECT_EQ(std::count(kinds.begin(), kinds.end(), "reconnect"), 10);
}

// A device that had come out of an outage, but not for recovery_polls polls
// yet, when the poller stops is not left looking as if it still failed.
TEST(DevicePoller, AnOutageEndingAtTheStopIsClosedAtItsFirstGoodPoll) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->reads_failing_from = 4;
  source->reads_failing_count = 1;
  DevicePollerOptions options{10ms, 10ms, 80ms, 6};  // reads 0-5: one good read after the failure
  options.recovery_polls = 3;
  const auto stats = h.run(std::move(source), options, 800ms);
  EXPECT_EQ(stats.polls_failed, 1);
  EXPECT_EQ(stats.reconnects, 1);
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "disconnect", "reconnect", "stopped"}));
}

// A device that answers with an exception keeps its link: the samples say
// bad-reply with the device's code, and the link is not torn down.
TEST(DevicePoller, BadRepliesKeepTheLinkAndTheirCode) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->reads_failing_from = 2;
  source->reads_failing_count = 3;
  source->failure_status = SampleStatus::kBadReply;
  source->failure_raw = 2;  // Modbus "illegal data address"
  const auto counters = source->counters;
  h.run(std::move(source), {10ms, 10ms, 40ms, {}}, 400ms);
  const auto samples = h.store.read_samples(h.channels[1]);
  ASSERT_GT(samples.size(), 5u);
  for (int i = 2; i < 5; ++i) {
    EXPECT_EQ(samples[i].status, SampleStatus::kBadReply);
    EXPECT_EQ(samples[i].raw, 2.0);
    EXPECT_FALSE(samples[i].value.has_value());
  }
  EXPECT_EQ(samples[5].status, SampleStatus::kOpenCircuit) << "the channel's own status came back";
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "bad-reply", "recovered"}));
  EXPECT_EQ(counters->connects.load(), 1) << "a device that answers was reconnected";
  EXPECT_EQ(counters->disconnects.load(), 1) << "only the final close";
}

// A bug below the poller (anything that is not a DeviceError) is recorded
// and the device goes on; it never ends the process.
TEST(DevicePoller, AnUnexpectedExceptionIsRecordedAndThePollerGoesOn) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->reads_failing_from = 2;
  source->reads_failing_count = 1;
  source->throw_unexpected = true;
  const auto stats = h.run(std::move(source), {10ms, 10ms, 40ms, {}}, 700ms);
  EXPECT_GE(stats.polls_ok, 10) << "the poller did not go on after the failure";
  const auto events = h.store.events();
  const auto error = std::find_if(events.begin(), events.end(), [](const auto& e) { return e.kind == "error"; });
  ASSERT_NE(error, events.end());
  EXPECT_NE(error->message.find("a bug in a device driver"), std::string::npos) << error->message;
}

// A read that never returns does not hold the stop: the poller is abandoned
// after the grace period, and nothing it reads later reaches the run.
TEST(DevicePoller, AStuckReadIsAbandonedAtTheStop) {
  Harness h;
  auto source = std::make_unique<ScriptedSource>();
  source->read_time = 3s;
  storage::RunWriter writer(h.store, {20ms, 10'000});
  const auto poller = std::make_shared<DevicePoller>(std::move(source), h.device, h.channels, writer,
                                                     DevicePollerOptions{20ms, 20ms, 80ms, {}});
  poller->start();
  std::this_thread::sleep_for(100ms);
  const auto before = std::chrono::steady_clock::now();
  EXPECT_FALSE(poller->stop(300ms)) << "the stuck read was waited for";
  EXPECT_LT(std::chrono::steady_clock::now() - before, 1s);
  writer.stop();
  EXPECT_EQ(writer.stats().uncommitted_at_stop, 0) << "the abandoned poller pushed into a stopped writer";
  EXPECT_EQ(h.event_kinds(), (std::vector<std::string>{"connect", "abandoned"}));
  EXPECT_TRUE(h.store.read_samples(h.channels[0]).empty());
}

TEST(DevicePoller, StartingAPollerThatNoSharedPtrOwnsIsRefused) {
  Harness h;
  storage::RunWriter writer(h.store);
  DevicePoller poller(std::make_unique<ScriptedSource>(), h.device, h.channels, writer, {20ms, 20ms, 80ms, {}});
  EXPECT_THROW(poller.start(), std::logic_error);
}

TEST(DevicePoller, StopsAfterItsPollCount) {
  Harness h;
  const auto stats = h.run(std::make_unique<ScriptedSource>(), {10ms, 250ms, 10s, 7}, 400ms);
  EXPECT_EQ(stats.polls_ok, 7);
  EXPECT_EQ(h.store.read_samples(h.channels[0]).size(), 7u);
  EXPECT_EQ(h.event_kinds().back(), "stopped");
}

TEST(DevicePoller, InvalidOptionsAreRefused) {
  DevicePollerOptions no_recovery;
  no_recovery.recovery_polls = 0;
  EXPECT_NE(no_recovery.Validate(), "");
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
