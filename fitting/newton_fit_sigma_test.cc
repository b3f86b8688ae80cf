// Newton fits weighted by each sample's own σ (a BOS probe's samples each
// carry theirs): absolute uncertainties that cover the truth as often as
// they claim, and samples weighted by how well they are known.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "fitting/newton_fit.h"
#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

using Curve = testing::CoolingCurve;

// 40 frames every 10 s whose σ grows from 0.05 to 1 °C (a probe that loses
// contrast as the plume fades), with noise of exactly that σ.
struct WeightedRecord {
  std::vector<double> time_s, temperature_c, sigma_c;
};

WeightedRecord heteroscedastic(const Curve& curve, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  WeightedRecord r;
  for (int i = 0; i < 40; ++i) {
    const double t = 10.0 * i, sigma = 0.05 + 0.95 * i / 39.0;
    r.time_s.push_back(t);
    r.sigma_c.push_back(sigma);
    r.temperature_c.push_back(curve.at(t) + sigma * unit(random));
  }
  return r;
}

TEST(NewtonFitSigma, PerSampleSigmaGivesAbsoluteIntervalsThatCoverTheTruth) {
  const Curve curve{22.0, 80.0, 0.006};
  int covered = 0, fits = 0;
  double chi_square_sum = 0;
  for (unsigned seed = 1; seed <= 200; ++seed) {
    const auto r = heteroscedastic(curve, seed);
    const NewtonFit f = fit_newton(r.time_s, r.temperature_c, r.sigma_c);
    ASSERT_TRUE(f.ok()) << f.brief_report();
    ASSERT_TRUE(f.summary.absolute_sigma);
    ASSERT_TRUE(f.summary.reduced_chi_square);
    chi_square_sum += *f.summary.reduced_chi_square;
    ++fits;
    if (f.k_per_s.low <= curve.k_per_s && curve.k_per_s <= f.k_per_s.high) ++covered;
  }
  // 95% intervals: 190 of 200 expected; binomial sd 3.1.
  EXPECT_GE(covered, 180) << covered << " of " << fits;
  EXPECT_LE(covered, 199) << covered << " of " << fits;
  EXPECT_NEAR(chi_square_sum / fits, 1.0, 0.05) << "the σ given are the noise's: reduced χ² averages 1";
}

TEST(NewtonFitSigma, OneSigmaForEverySampleIsTheKnownMeasurementSigma) {
  const Curve curve{22.0, 80.0, 0.006};
  const auto record = testing::sample_cooling(curve, 60, 5.0, 0.2, 9);
  const std::vector<double> sigma(record.time_s.size(), 0.2);
  NewtonFitOptions known;
  known.measurement_sigma_c = 0.2;
  const NewtonFit one = fit_newton(record.time_s, record.temperature_c, known);
  const NewtonFit each = fit_newton(record.time_s, record.temperature_c, sigma);
  ASSERT_TRUE(one.ok() && each.ok());
  EXPECT_NEAR(each.k_per_s.value, one.k_per_s.value, 1e-12);
  EXPECT_NEAR(each.k_per_s.std_error, one.k_per_s.std_error, 1e-12 + 1e-9 * one.k_per_s.std_error);
  EXPECT_NEAR(each.t0_c.std_error, one.t0_c.std_error, 1e-9);
  EXPECT_NEAR(*each.summary.reduced_chi_square, *one.summary.reduced_chi_square, 1e-9);
}

TEST(NewtonFitSigma, SamplesKnownPoorlyPullTheFitLittle) {
  // The last 20 of 40 samples read 3 °C warm but carry σ = 5 °C.
  const Curve curve{22.0, 80.0, 0.006};
  std::vector<double> t, y, sigma;
  for (int i = 0; i < 40; ++i) {
    t.push_back(10.0 * i);
    y.push_back(curve.at(10.0 * i) + (i >= 20 ? 3.0 : 0.0));
    sigma.push_back(i >= 20 ? 5.0 : 0.05);
  }
  const NewtonFit weighted = fit_newton(t, y, sigma);
  const NewtonFit unweighted = fit_newton(t, y);
  ASSERT_TRUE(weighted.ok() && unweighted.ok());
  EXPECT_LT(std::abs(weighted.k_per_s.value - curve.k_per_s), 0.1 * std::abs(unweighted.k_per_s.value - curve.k_per_s));
  EXPECT_NEAR(weighted.k_per_s.value, curve.k_per_s, 0.02 * curve.k_per_s);
}

TEST(NewtonFitSigma, BadSigmasAreRefusedOrLeftOut) {
  const std::vector<double> t = {0, 10, 20, 30, 40, 50}, y = {80, 75, 70, 66, 62, 59};
  EXPECT_THROW(fit_newton(t, y, std::vector<double>{0.1, 0.1, 0.0, 0.1, 0.1, 0.1}), std::invalid_argument);
  EXPECT_THROW(fit_newton(t, y, std::vector<double>{0.1, 0.1}), std::invalid_argument);
  const NewtonFit dropped = fit_newton(t, y, std::vector<double>{0.1, NAN, 0.1, 0.1, INFINITY, 0.1});
  EXPECT_EQ(dropped.summary.rejected_non_finite, 2u);
  EXPECT_EQ(dropped.summary.points_used, 4u);
  NewtonFitOptions both;
  both.measurement_sigma_c = 0.1;
  const NewtonFit refused = fit_newton(t, y, std::vector<double>(6, 0.1), both);
  EXPECT_EQ(refused.summary.status, FitStatus::kInvalidOptions);
  EXPECT_NE(refused.summary.message.find("one or the other"), std::string::npos);
}

TEST(NewtonFitSigma, ACleanSeriesKeepsEachSigmaWithItsSample) {
  const std::vector<double> t = {30, 0, 10, 20}, y = {66, 80, 75, 70}, sigma = {0.4, 0.1, 0.2, 0.3};
  const CleanSeries s = clean_series(t, y, sigma, 0.0);
  EXPECT_EQ(s.time_s, (std::vector<double>{0, 10, 20, 30}));
  EXPECT_EQ(s.sigma_c, (std::vector<double>{0.1, 0.2, 0.3, 0.4}));
  EXPECT_TRUE(clean_series(t, y, 0.0).sigma_c.empty());
}

}  // namespace
}  // namespace bosfuse::fitting
