// The alarm rules on scripted samples: each kind raised once and cleared
// once, the hysteresis of low and high, a least-squares rate that noise does
// not raise, and stale channels that fail or never answered.

#include "acquisition/alarm_monitor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bosfuse::acquisition {
namespace {

using storage::SampleStatus;

constexpr std::int64_t kStartNs = 1'700'000'000'000'000'000;
constexpr std::int64_t kChannel = 7;

std::int64_t at(double seconds) { return kStartNs + std::llround(seconds * 1e9); }

AlarmMonitor monitor_with(AlarmLimits limits) {
  return AlarmMonitor({{kChannel, "T1", "degC", limits}, {8, "T2", "degC", {}}}, kStartNs);
}

// Everything `monitor` says while it is fed `values`, one a second from t = 0.
std::vector<AlarmTransition> feed(AlarmMonitor& monitor, const std::vector<double>& values, double t0_s = 0) {
  std::vector<AlarmTransition> all;
  for (std::size_t i = 0; i < values.size(); ++i) {
    for (auto& t : monitor.add_sample(kChannel, at(t0_s + double(i)), SampleStatus::kOk, values[i])) {
      all.push_back(std::move(t));
    }
  }
  return all;
}

std::vector<std::string> messages(const std::vector<AlarmTransition>& transitions) {
  std::vector<std::string> out;
  for (const auto& t : transitions) out.push_back(t.event_kind() + " " + t.message);
  return out;
}

TEST(AlarmMonitor, HighIsRaisedOnceAndClearedOnceBeyondTheHysteresis) {
  AlarmMonitor monitor = monitor_with({{}, 80.0, {}, {}});
  // The hysteresis of 80 is 0.8: 79.5 and 80.0 are not yet back inside.
  const auto transitions = feed(monitor, {79, 85.2, 86, 81, 79.5, 80.0, 80.5, 79.1, 79.9, 80.0, 80.4});
  EXPECT_EQ(messages(transitions), (std::vector<std::string>{"alarm T1: high 85.2 degC above the limit 80 degC",
                                                             "alarm-cleared T1: high cleared at 79.1 degC",
                                                             "alarm T1: high 80.4 degC above the limit 80 degC"}));
  ASSERT_EQ(transitions.size(), 3u);
  EXPECT_EQ(transitions[0].channel_id, kChannel);
  EXPECT_EQ(transitions[0].kind, AlarmKind::kHigh);
  EXPECT_TRUE(transitions[0].raised);
  EXPECT_EQ(transitions[0].t_ns, at(1));
  EXPECT_FALSE(transitions[1].raised);
  EXPECT_EQ(transitions[1].t_ns, at(7));
  EXPECT_TRUE(monitor.active(kChannel, AlarmKind::kHigh));
}

TEST(AlarmMonitor, LowHasAHysteresisOfAtLeastATenthOfAUnit) {
  AlarmMonitor monitor = monitor_with({0.5, {}, {}, {}});  // 1% of 0.5 is less than 0.1
  EXPECT_EQ(messages(feed(monitor, {1.0, 0.45, 0.3, 0.55, 0.59, 0.62, 0.7})),
            (std::vector<std::string>{"alarm T1: low 0.450 degC below the limit 0.5 degC",
                                      "alarm-cleared T1: low cleared at 0.620 degC"}));
  EXPECT_EQ(AlarmMonitor::hysteresis(0.5), 0.1);
  EXPECT_EQ(AlarmMonitor::hysteresis(-200), 2.0);
}

TEST(AlarmMonitor, ALowAndAHighLimitAreJudgedApart) {
  AlarmMonitor monitor = monitor_with({10.0, 20.0, {}, {}});
  EXPECT_EQ(messages(feed(monitor, {15, 25, 5, 15})),
            (std::vector<std::string>{
                "alarm T1: high 25.0 degC above the limit 20 degC", "alarm-cleared T1: high cleared at 5.0 degC",
                "alarm T1: low 5.0 degC below the limit 10 degC", "alarm-cleared T1: low cleared at 15.0 degC"}));
}

// A failed poll or a burnt-out input is no value: it neither raises nor
// clears, whatever number came with it.
TEST(AlarmMonitor, SamplesThatAreNotOkNeitherRaiseNorClear) {
  AlarmMonitor monitor = monitor_with({0.0, 80.0, 1.0, {}});
  for (int i = 0; i < 30; ++i) {
    EXPECT_TRUE(monitor.add_sample(kChannel, at(i), SampleStatus::kOpenCircuit, std::nullopt).empty());
    EXPECT_TRUE(monitor.add_sample(kChannel, at(i + 0.5), SampleStatus::kOutOfRange, 1e6 * i).empty());
  }
  EXPECT_EQ(monitor.add_sample(kChannel, at(40), SampleStatus::kOk, 90.0).size(), 1u);
  EXPECT_TRUE(monitor.add_sample(kChannel, at(41), SampleStatus::kTimeout, 20.0).empty());
  EXPECT_TRUE(monitor.add_sample(kChannel, at(42), SampleStatus::kOk, std::nan("")).empty());
  EXPECT_TRUE(monitor.active(kChannel, AlarmKind::kHigh)) << "a value that is not ok cleared the alarm";
}

TEST(AlarmMonitor, ChannelsWithoutLimitsAreNotWatched) {
  AlarmMonitor monitor = monitor_with({{}, 80.0, {}, 1.0});
  EXPECT_TRUE(monitor.add_sample(8, at(1), SampleStatus::kOk, 1000.0).empty());
  EXPECT_TRUE(monitor.add_sample(99, at(1), SampleStatus::kOk, 1000.0).empty());
  const auto stale = monitor.check_stale(at(100));
  ASSERT_EQ(stale.size(), 1u) << "only T1 has a stale limit";
  EXPECT_EQ(stale[0].channel_id, kChannel);
  EXPECT_TRUE(AlarmMonitor({{1, "a", "degC", {}}}, kStartNs).empty());
  EXPECT_THROW(AlarmMonitor({{1, "a", "degC", {5.0, 1.0, {}, {}}}}, kStartNs), std::invalid_argument);
}

TEST(AlarmMonitor, RateIsTheLeastSquaresSlopeOnceTenSecondsAndThreeSamplesAreIn) {
  AlarmMonitor monitor = monitor_with({{}, {}, 10.0, {}});
  std::vector<double> ramp;  // 12.5 degC/min, exactly
  for (int i = 0; i <= 15; ++i) ramp.push_back(20.0 + 12.5 / 60.0 * i);
  const auto transitions = feed(monitor, ramp);
  EXPECT_EQ(messages(transitions),
            (std::vector<std::string>{"alarm T1: rate 12.5 degC/min beyond the limit 10 degC/min"}));
  ASSERT_EQ(transitions.size(), 1u);
  EXPECT_EQ(transitions[0].t_ns, at(10)) << "judged before 10 s of values, or later";

  // Two values 20 s apart are too few to judge, however steep.
  AlarmMonitor two = monitor_with({{}, {}, 10.0, {}});
  EXPECT_TRUE(two.add_sample(kChannel, at(0), SampleStatus::kOk, 0.0).empty());
  EXPECT_TRUE(two.add_sample(kChannel, at(20), SampleStatus::kOk, 500.0).empty());
}

// Noise of 0.5 degC at 1 Hz: the difference of two successive readings
// changes by ~40 degC/min, a 60 s least-squares slope by a fraction of one.
TEST(AlarmMonitor, NoisyReadingsDoNotRaiseRateButARealRampDoesOnce) {
  std::mt19937 random(12);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::vector<double> values;
  for (int i = 0; i < 300; ++i) values.push_back(50.0 + noise(random));  // 5 min flat
  values[200] += 5.0;                                                    // and one wild reading
  double largest_step_per_min = 0;
  for (std::size_t i = 1; i < values.size(); ++i) {
    largest_step_per_min = std::max(largest_step_per_min, std::fabs(values[i] - values[i - 1]) * 60.0);
  }
  ASSERT_GT(largest_step_per_min, 100.0) << "the test's noise would not fool a two-point rate";
  for (int i = 0; i < 120; ++i) values.push_back(50.0 + 15.0 / 60.0 * i + noise(random));  // 2 min at 15/min
  for (int i = 0; i < 240; ++i) values.push_back(80.0 + noise(random));                    // 4 min flat again

  AlarmMonitor monitor = monitor_with({{}, {}, 10.0, {}});
  const auto transitions = feed(monitor, values);
  ASSERT_EQ(transitions.size(), 2u) << ::testing::PrintToString(messages(transitions));
  EXPECT_TRUE(transitions[0].raised);
  EXPECT_EQ(transitions[0].message.substr(0, 9), "T1: rate ");
  EXPECT_GT(transitions[0].t_ns, at(300)) << "raised by noise before the ramp";
  EXPECT_LT(transitions[0].t_ns, at(360)) << "the ramp took too long to be seen";
  EXPECT_FALSE(transitions[1].raised);
  EXPECT_EQ(transitions[1].message.substr(0, 22), "T1: rate cleared at 9.") << transitions[1].message;
  EXPECT_GT(transitions[1].t_ns, at(420)) << "cleared while still rising";
}

TEST(AlarmMonitor, AFallingRateCountsToo) {
  AlarmMonitor monitor = monitor_with({{}, {}, 10.0, {}});
  std::vector<double> fall;
  for (int i = 0; i <= 12; ++i) fall.push_back(100.0 - 0.5 * i);  // −30 degC/min
  EXPECT_EQ(messages(feed(monitor, fall)),
            (std::vector<std::string>{"alarm T1: rate -30.0 degC/min beyond the limit 10 degC/min"}));
}

// A channel whose polls fail is stale once its last ok value is older than
// the limit: raised once, however many checks and failed samples follow,
// and cleared by the next ok value.
TEST(AlarmMonitor, StaleIsRaisedOnceWhileSamplesFailAndClearedByAValue) {
  AlarmMonitor monitor = monitor_with({{}, {}, {}, 10.0});
  EXPECT_TRUE(monitor.add_sample(kChannel, at(0), SampleStatus::kOk, 25.0).empty());
  std::vector<AlarmTransition> raised;
  for (int i = 1; i <= 20; ++i) {
    EXPECT_TRUE(monitor.add_sample(kChannel, at(i), SampleStatus::kTimeout, std::nullopt).empty());
    for (auto& t : monitor.check_stale(at(i + 0.5))) raised.push_back(t);
  }
  EXPECT_EQ(messages(raised), (std::vector<std::string>{"alarm T1: stale no value for 10.5 s (limit 10 s)"}));
  ASSERT_EQ(raised.size(), 1u);
  EXPECT_EQ(raised[0].kind, AlarmKind::kStale);
  EXPECT_EQ(raised[0].t_ns, at(10.5));
  EXPECT_EQ(messages(monitor.add_sample(kChannel, at(21), SampleStatus::kOk, 24.0)),
            (std::vector<std::string>{"alarm-cleared T1: stale cleared at 24.0 degC (no value for 21.0 s)"}));
  EXPECT_TRUE(monitor.check_stale(at(30)).empty());
  EXPECT_EQ(monitor.check_stale(at(31.2)).size(), 1u) << "stale again 10 s after the last value";
}

TEST(AlarmMonitor, AChannelThatNeverHadAValueGoesStaleFromTheStart) {
  AlarmMonitor monitor = monitor_with({{}, 80.0, {}, 10.0});
  EXPECT_TRUE(monitor.add_sample(kChannel, at(3), SampleStatus::kOpenCircuit, std::nullopt).empty());
  EXPECT_TRUE(monitor.check_stale(at(9.9)).empty());
  EXPECT_TRUE(monitor.check_stale(at(10)).empty()) << "raised at the limit, not beyond it";
  EXPECT_EQ(messages(monitor.check_stale(at(12))),
            (std::vector<std::string>{"alarm T1: stale no value for 12.0 s (limit 10 s)"}));
  EXPECT_TRUE(monitor.check_stale(at(60)).empty());
}

TEST(AlarmMonitor, MessagesWithoutAUnitAndKindNames) {
  AlarmMonitor monitor({{1, "flow", "", {{}, 2.0, 0.5, {}}}}, kStartNs);
  EXPECT_EQ(monitor.add_sample(1, at(0), SampleStatus::kOk, 2.5).at(0).message, "flow: high 2.5 above the limit 2");
  for (int i = 1; i <= 10; ++i) monitor.add_sample(1, at(i), SampleStatus::kOk, 2.5 + i);
  EXPECT_TRUE(monitor.active(1, AlarmKind::kRate));
  EXPECT_EQ(to_string(AlarmKind::kLow), "low");
  EXPECT_EQ(to_string(AlarmKind::kHigh), "high");
  EXPECT_EQ(to_string(AlarmKind::kRate), "rate");
  EXPECT_EQ(to_string(AlarmKind::kStale), "stale");
}

// A fast poll keeps thousands of values in the 60 s window; the slope of a
// long exact ramp stays exact (the window's sums do not drift).
TEST(AlarmMonitor, TheRateWindowStaysExactOverLongRuns) {
  AlarmMonitor monitor = monitor_with({{}, {}, 6.0, {}});
  std::vector<AlarmTransition> all;
  for (int i = 0; i < 200'000; ++i) {  // 100 ms polls for 5.5 h at 5.9 degC/min
    for (auto& t : monitor.add_sample(kChannel, at(0.1 * i), SampleStatus::kOk, 1000.0 + 5.9 / 600.0 * i)) {
      all.push_back(t);
    }
  }
  EXPECT_TRUE(all.empty()) << ::testing::PrintToString(messages(all));
  const auto steeper = monitor.add_sample(kChannel, at(20'000), SampleStatus::kOk, 1000.0 + 5.9 / 600.0 * 200'000 + 60);
  ASSERT_EQ(steeper.size(), 1u) << "a jump of 60 degC in a 60 s window went unseen";
}

}  // namespace
}  // namespace bosfuse::acquisition
