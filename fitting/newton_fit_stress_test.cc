// Numerical stress for the Newton fit: inputs that break naive fitters.
// Each case must give a correct fit or a clear error, never a silent wrong
// number.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "fitting/newton_fit.h"
#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

using testing::CoolingCurve;
using testing::CoolingRecord;
using testing::sample_cooling;

NewtonFit fit_stressed(const CoolingRecord& r, const NewtonFitOptions& options = {}) {
  return fit_newton(r.time_s, r.temperature_c, options);
}

// "Correct" for a fit that claims success: the truth lies within 4 standard
// errors (a 1-in-15,000 event for honest errors).
void expect_correct(const NewtonFit& result, const CoolingCurve& curve) {
  ASSERT_TRUE(result.ok()) << result.brief_report();
  EXPECT_NEAR(result.k_per_s.value, curve.k_per_s, 4 * result.k_per_s.std_error + 1e-12) << result.brief_report();
  EXPECT_NEAR(result.t0_c.value, curve.t0_c, 4 * result.t0_c.std_error + 1e-9) << result.brief_report();
  EXPECT_NEAR(result.ambient_c.value, curve.ambient_c, 4 * result.ambient_c.std_error + 1e-9) << result.brief_report();
}

void expect_clear_error(const NewtonFit& result) {
  EXPECT_FALSE(result.ok());
  EXPECT_FALSE(result.summary.message.empty());
  EXPECT_TRUE(std::isnan(result.k_per_s.value));
  EXPECT_TRUE(std::isnan(result.t0_c.value));
}

TEST(NewtonFitStress, EpochScaleTimestampsGiveTheSameFitAsRelativeOnes) {
  const CoolingCurve curve;
  const auto relative = sample_cooling(curve, 600, 0.5, 0.05, 3, 0.0);
  auto epoch = relative;
  for (double& t : epoch.time_s) t += 1.8e9;  // 2027-01-15: seconds since 1970
  const auto a = fit_stressed(relative);
  const auto b = fit_stressed(epoch);
  expect_correct(b, curve);
  EXPECT_EQ(b.origin_s, 1.8e9);
  // Epoch-scale doubles carry ~2e-7 s of rounding per timestamp; the fits agree far below their uncertainty.
  EXPECT_NEAR(b.k_per_s.value, a.k_per_s.value, 1e-6 * a.k_per_s.value);
  EXPECT_NEAR(b.k_per_s.std_error, a.k_per_s.std_error, 1e-4 * a.k_per_s.std_error);
  EXPECT_NEAR(b.temperature_at(1.8e9 + 100.0), curve.at(100.0), 0.05);
}

TEST(NewtonFitStress, TemperaturesANoiseLevelAboveAmbientFitOrFailClearly) {
  const CoolingCurve curve{22.0, 22.2, 0.01};  // ΔT = 0.2 °C with σ = 0.2 °C noise
  NewtonFitOptions fixed;
  fixed.ambient = AmbientModel::fixed(curve.ambient_c);
  // Many points resolve it with a fixed ambient, with honest (wide) errors.
  const auto many = fit_stressed(sample_cooling(curve, 5000, 0.1, 0.2, 8), fixed);
  expect_correct(many, curve);
  EXPECT_GT(many.k_per_s.std_error, 0.05 * curve.k_per_s) << "such a fit cannot be precise";
  // Few points and a free ambient cannot; they must say so or be right.
  const auto few = fit_stressed(sample_cooling(curve, 30, 10.0, 0.2, 9));
  if (few.ok()) {
    expect_correct(few, curve);
  } else {
    expect_clear_error(few);
  }
}

TEST(NewtonFitStress, AMillionPointsFit) {
  const CoolingCurve curve{20.0, 60.0, 0.002};
  const auto r = sample_cooling(curve, 1'000'000, 0.002, 0.5, 10, 1.7e9);
  const auto result = fit_stressed(r);
  expect_correct(result, curve);
  EXPECT_EQ(result.summary.points_used, 1'000'000u);
  EXPECT_LT(result.k_per_s.std_error, 1e-3 * curve.k_per_s);
}

TEST(NewtonFitStress, NonFiniteSamplesAreRejectedAndCounted) {
  const CoolingCurve curve;
  const auto clean = sample_cooling(curve, 300, 1.0, 0.05, 4);
  auto dirty = clean;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  dirty.time_s.push_back(kNaN);
  dirty.temperature_c.push_back(40.0);
  dirty.time_s.push_back(50.5);
  dirty.temperature_c.push_back(kInf);
  dirty.time_s.push_back(kInf);
  dirty.temperature_c.push_back(kNaN);
  dirty.time_s.push_back(70.5);
  dirty.temperature_c.push_back(-kInf);
  dirty.time_s.insert(dirty.time_s.begin(), -kInf);  // also before everything: must not become the origin
  dirty.temperature_c.insert(dirty.temperature_c.begin(), 99.0);
  const auto a = fit_stressed(clean);
  const auto b = fit_stressed(dirty);
  ASSERT_TRUE(b.ok()) << b.brief_report();
  EXPECT_EQ(b.summary.rejected_non_finite, 5u);
  EXPECT_EQ(b.summary.points_used, 300u);
  EXPECT_EQ(b.origin_s, 0.0);
  EXPECT_DOUBLE_EQ(b.k_per_s.value, a.k_per_s.value);
  EXPECT_NE(b.summary.brief_report().find("5 rejected"), std::string::npos);
}

TEST(NewtonFitStress, UnsortedTimesAreSortedAndDuplicatesKept) {
  const CoolingCurve curve;
  const auto sorted = sample_cooling(curve, 400, 1.0, 0.05, 12);
  auto shuffled = sorted;
  std::vector<std::size_t> order(sorted.time_s.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937_64(99));
  for (std::size_t i = 0; i < order.size(); ++i) {
    shuffled.time_s[i] = sorted.time_s[order[i]];
    shuffled.temperature_c[i] = sorted.temperature_c[order[i]];
  }
  const auto a = fit_stressed(sorted);
  const auto b = fit_stressed(shuffled);
  ASSERT_TRUE(b.ok());
  EXPECT_NEAR(b.k_per_s.value, a.k_per_s.value, 1e-10 * a.k_per_s.value);
  EXPECT_EQ(b.origin_s, 0.0);

  auto doubled = sorted;  // every 10th time measured twice, with its own noise
  std::mt19937_64 random(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (std::size_t i = 0; i < sorted.time_s.size(); i += 10) {
    doubled.time_s.push_back(sorted.time_s[i]);
    doubled.temperature_c.push_back(curve.at(sorted.time_s[i]) + noise(random));
  }
  const auto c = fit_stressed(doubled);
  expect_correct(c, curve);
  EXPECT_EQ(c.summary.duplicate_times, 40u);
  EXPECT_EQ(c.summary.points_used, 440u) << "duplicates are kept, not averaged";
}

CoolingRecord with_outliers(const CoolingRecord& r, double every, double size_c) {
  auto spoiled = r;
  for (std::size_t i = 7; i < spoiled.temperature_c.size(); i += static_cast<std::size_t>(every)) {
    spoiled.temperature_c[i] += size_c;
  }
  return spoiled;
}

TEST(NewtonFitStress, OutliersWithoutRobustLossAreFlaggedAndWidenTheErrors) {
  const CoolingCurve curve;
  const auto spoiled = with_outliers(sample_cooling(curve, 500, 1.0, 0.05, 13), 20, 5.0);
  const auto plain = fit_stressed(spoiled);
  ASSERT_TRUE(plain.ok()) << plain.brief_report();
  EXPECT_EQ(plain.summary.outliers, 25u);
  bool suggested = false;
  for (const auto& w : plain.summary.warnings) suggested |= w.find("--loss huber") != std::string::npos;
  EXPECT_TRUE(suggested) << plain.brief_report();
  // The spikes inflate s, and with it the errors, so the interval still covers.
  EXPECT_NEAR(plain.k_per_s.value, curve.k_per_s, 4 * plain.k_per_s.std_error);
}

TEST(NewtonFitStress, RobustLossIgnoresOutliers) {
  const CoolingCurve curve;
  const auto honest = sample_cooling(curve, 500, 1.0, 0.05, 13);
  const auto spoiled = with_outliers(honest, 20, 5.0);
  for (auto loss : {RobustLoss::huber(0.1), RobustLoss::cauchy(0.1)}) {
    NewtonFitOptions options;
    options.loss = loss;
    const auto robust = fit_stressed(spoiled, options);
    expect_correct(robust, curve);
    const auto reference = fit_stressed(honest);
    // Close to the fit of the data without the spikes, and much more precise than the plain fit of the spoiled data.
    EXPECT_NEAR(robust.k_per_s.value, reference.k_per_s.value, 2 * reference.k_per_s.std_error);
    EXPECT_LT(robust.k_per_s.std_error, 0.5 * fit_stressed(spoiled).k_per_s.std_error);
  }
}

TEST(NewtonFitStress, AFlatRecordIsAClearError) {
  const CoolingCurve flat{22.0, 22.0, 0.01};
  for (unsigned seed = 0; seed < 5; ++seed) {
    const auto result = fit_stressed(sample_cooling(flat, 300, 1.0, 0.05, seed));
    expect_clear_error(result);
    EXPECT_TRUE(result.summary.status == FitStatus::kNoDecay || result.summary.status == FitStatus::kRankDeficient ||
                result.summary.status == FitStatus::kUnidentifiable)
        << to_string(result.summary.status);
  }
  const std::vector<double> t{0, 1, 2, 3, 4, 5}, exactly_flat(6, 22.0);
  expect_clear_error(fit_newton(t, exactly_flat));
}

TEST(NewtonFitStress, ARisingRecordTowardsAWarmerAmbientIsNewtonsLawToo) {
  const CoolingCurve warming{30.0, 15.0, 0.02};  // a cold probe warming up in 30 °C air
  const auto result = fit_stressed(sample_cooling(warming, 400, 0.5, 0.05, 14));
  expect_correct(result, warming);
  EXPECT_LT(result.t0_c.value, result.ambient_c.value);
}

TEST(NewtonFitStress, AStraightLineWithFreeAmbientCannotGiveKAndSaysWhy) {
  CoolingRecord line;
  for (int i = 0; i < 200; ++i) {
    line.time_s.push_back(i);
    line.temperature_c.push_back(60.0 - 0.01 * i);
  }
  const auto result = fit_stressed(line);
  expect_clear_error(result);
  EXPECT_NE(result.summary.message.find("fix the ambient"), std::string::npos) << result.summary.message;
  // With the ambient known the excess over ambient gives k: it falls from
  // 40 to 38.01 °C over 199 s.
  NewtonFitOptions fixed;
  fixed.ambient = AmbientModel::fixed(20.0);
  const auto known = fit_stressed(line, fixed);
  ASSERT_TRUE(known.ok()) << known.brief_report();
  const double expected_k = std::log(40.0 / 38.01) / 199.0;
  EXPECT_NEAR(known.k_per_s.value, expected_k, 0.01 * expected_k);
}

TEST(NewtonFitStress, AllSamplesAtOneTimeIsAnError) {
  const std::vector<double> t(10, 5.0), y{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  const auto result = fit_newton(t, y);
  EXPECT_EQ(result.summary.status, FitStatus::kNoTimeSpan);
  expect_clear_error(result);
}

TEST(NewtonFitStress, ADecayFasterThanTheSamplingIsAnError) {
  const CoolingCurve fast{20.0, 80.0, 5.0};  // τ = 0.2 s, sampled every 2 s
  const auto result = fit_stressed(sample_cooling(fast, 100, 2.0, 0.05, 15));
  expect_clear_error(result);
}

TEST(NewtonFitStress, HittingTheIterationLimitIsAnError) {
  NewtonFitOptions options;
  options.max_iterations = 1;
  const auto result = fit_stressed(sample_cooling(CoolingCurve{}, 300, 1.0, 0.05, 16), options);
  EXPECT_EQ(result.summary.status, FitStatus::kNotConverged);
  expect_clear_error(result);
}

}  // namespace
}  // namespace bosfuse::fitting
