#include "fusion/time_alignment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace bosfuse::fusion {
namespace {

TEST(TimeAlignment, LinearInsideTheSpanFlaggedOutside) {
  const std::vector<double> t{0, 1, 2, 3}, value{10, 12, 14, 13};
  const std::vector<double> frames{-0.5, 0, 0.25, 2.5, 3, 3.5};
  const auto aligned = align_to_frames(t, value, frames);
  EXPECT_FALSE(aligned.ok(0));
  EXPECT_TRUE(std::isnan(aligned.value[0]));
  EXPECT_DOUBLE_EQ(aligned.value[1], 10);
  EXPECT_DOUBLE_EQ(aligned.value[2], 10.5);
  EXPECT_DOUBLE_EQ(aligned.value[3], 13.5);
  EXPECT_DOUBLE_EQ(aligned.value[4], 13);
  EXPECT_FALSE(aligned.ok(5));
  EXPECT_EQ(aligned.outside, 2u);
}

TEST(TimeAlignment, OffsetMovesTheFramesOnTheHostClock) {
  const std::vector<double> t{0, 10}, value{0, 100};
  const std::vector<double> frames{1, 2};
  const auto aligned = align_to_frames(t, value, frames, 0.5);  // frames happened 0.5 s later
  EXPECT_DOUBLE_EQ(aligned.value[0], 15);
  EXPECT_DOUBLE_EQ(aligned.value[1], 25);
}

TEST(TimeAlignment, NonFiniteSamplesAreSkippedAndUnsortedRefused) {
  const std::vector<double> t{0, 1, 2}, value{0, NAN, 20};
  const auto aligned = align_to_frames(t, value, std::vector<double>{1});
  EXPECT_DOUBLE_EQ(aligned.value[0], 10);
  EXPECT_THROW(align_to_frames(std::vector<double>{0, 2, 1}, value, std::vector<double>{1}), std::invalid_argument);
}

// A heater switched off at 10 s: flat, then an exponential decay. The
// thermocouple is read at 1 Hz; frames every 0.5 s on a camera clock 1.3 s
// behind the host, so frame t happened at host time t + 1.3.
struct Record {
  std::vector<double> tc_t, tc_value, frame_t, probe;
};

double rise_c(double t) { return t < 10 ? 40 : 40 * std::exp(-(t - 10) / 20); }

Record heater_off_record(double offset_s, bool with_feature, int first_frame = 4) {
  std::mt19937 random(4);
  std::normal_distribution<double> noise(0, 0.05);
  Record r;
  auto signal = [&](double t) { return with_feature ? rise_c(t) : 40 * std::exp(-t / 20); };
  for (int i = 0; i <= 80; ++i) {
    r.tc_t.push_back(i);
    r.tc_value.push_back(20 + signal(i) + noise(random));
  }
  for (int i = first_frame; i <= 140; ++i) {
    r.frame_t.push_back(0.5 * i);
    r.probe.push_back(0.02 * signal(0.5 * i + offset_s) + 0.1 * noise(random) / 5);
  }
  return r;
}

TEST(TimeAlignment, EstimatesAKnownCameraOffset) {
  const Record r = heater_off_record(1.3, true);
  const auto estimate = estimate_clock_offset(r.tc_t, r.tc_value, r.frame_t, r.probe);
  ASSERT_TRUE(estimate.ok) << estimate.message;
  EXPECT_NEAR(estimate.offset_s, 1.3, 0.1);
  EXPECT_GT(estimate.r2, 0.99);
  EXPECT_FALSE(estimate.at_search_edge);
}

TEST(TimeAlignment, APureExponentialCannotFixTheOffset) {
  const Record r = heater_off_record(1.3, false);
  const auto estimate = estimate_clock_offset(r.tc_t, r.tc_value, r.frame_t, r.probe);
  EXPECT_FALSE(estimate.ok);
  EXPECT_NE(estimate.message.find("no feature"), std::string::npos) << estimate.message;
}

TEST(TimeAlignment, AFeatureAtTheFirstFrameBoundsTheOffsetFromOneSideOnly) {
  // Frames from 10 s, when the heater goes off: later offsets see the same decay.
  const Record r = heater_off_record(0.0, true, 20);
  const auto estimate = estimate_clock_offset(r.tc_t, r.tc_value, r.frame_t, r.probe);
  EXPECT_FALSE(estimate.ok) << "offset " << estimate.offset_s;
  EXPECT_NE(estimate.message.find("on at least one side"), std::string::npos) << estimate.message;
}

TEST(TimeAlignment, AnOffsetBeyondTheSearchIsReportedAtItsEdge) {
  const Record r = heater_off_record(4.0, true);
  OffsetSearchOptions options;
  options.max_offset_s = 2;
  const auto estimate = estimate_clock_offset(r.tc_t, r.tc_value, r.frame_t, r.probe, options);
  EXPECT_FALSE(estimate.ok);
  EXPECT_TRUE(estimate.at_search_edge);
  options.step_s = 0;
  EXPECT_THROW(estimate_clock_offset(r.tc_t, r.tc_value, r.frame_t, r.probe, options), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fusion
