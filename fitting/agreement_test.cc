// Agreement of two fits and two series, on cases with known answers.

#include "fitting/agreement.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

// A successful fit carrying only the k a comparison reads.
NewtonFit fit_with_k(double k, double std_error) {
  NewtonFit fit;
  fit.summary.status = FitStatus::kOk;
  fit.k_per_s = {k, std_error, k - 1.96 * std_error, k + 1.96 * std_error, false};
  return fit;
}

CleanSeries series(double origin_s, std::vector<double> time_s, std::vector<double> temperature_c) {
  CleanSeries s;
  s.origin_s = origin_s;
  s.time_s = std::move(time_s);
  s.temperature_c = std::move(temperature_c);
  return s;
}

TEST(Agreement, KWithinTheCombinedUncertaintyAgree) {
  // Δk = −0.0005, combined σ = sqrt(0.0003² + 0.0004²) = 0.0005: z = −1.
  const auto result = compare_fits(fit_with_k(0.0100, 0.0003), fit_with_k(0.0105, 0.0004), {}, {});
  ASSERT_TRUE(result.k);
  EXPECT_NEAR(result.k->difference_per_s, -0.0005, 1e-15);
  EXPECT_NEAR(result.k->std_error_per_s, 0.0005, 1e-15);
  EXPECT_NEAR(result.k->z, -1.0, 1e-9);
  EXPECT_NEAR(result.k->relative_difference, -0.0005 / 0.01025, 1e-12);
  EXPECT_TRUE(result.k->agree);
  EXPECT_EQ(result.verdict.rfind("k agree within uncertainty", 0), 0u) << result.verdict;
  EXPECT_FALSE(result.series);
  EXPECT_NE(result.verdict.find("too few common times"), std::string::npos);
}

TEST(Agreement, KFurtherApartThanTheirUncertaintiesDiffer) {
  // Δk = −0.002, combined σ = 0.0001·√2: z = −14.14; 18.2% of the mean.
  const auto result = compare_fits(fit_with_k(0.010, 0.0001), fit_with_k(0.012, 0.0001), {}, {});
  ASSERT_TRUE(result.k);
  EXPECT_NEAR(result.k->z, -0.002 / (0.0001 * std::sqrt(2.0)), 1e-6);
  EXPECT_FALSE(result.k->agree);
  EXPECT_NE(result.verdict.find("k differ by -0.002 1/s (-18.2% of their mean, z = -14.1)"), std::string::npos)
      << result.verdict;
}

TEST(Agreement, TheThresholdFollowsTheConfidence) {
  const auto a = fit_with_k(0.010, 0.0001), b = fit_with_k(0.0102, 0.0001);  // z = −1.414
  AgreementOptions options;
  EXPECT_TRUE(compare_fits(a, b, {}, {}, options).k->agree);
  options.confidence = 0.80;  // critical 1.28
  EXPECT_FALSE(compare_fits(a, b, {}, {}, options).k->agree);
  options.confidence = 1.0;
  EXPECT_THROW(compare_fits(a, b, {}, {}, options), std::invalid_argument);
}

TEST(Agreement, AFailedFitIsNamedInsteadOfCompared) {
  NewtonFit failed;
  failed.summary.status = FitStatus::kNoDecay;
  failed.summary.message = "flat record";
  const auto result = compare_fits(fit_with_k(0.01, 0.001), failed, {}, {});
  EXPECT_FALSE(result.k);
  EXPECT_NE(result.verdict.find("BOS probe fit failed (flat record)"), std::string::npos) << result.verdict;
}

TEST(Agreement, AConstantOffsetIsABiasWithZeroSpread) {
  // a on 0..10 s; b = a + 0.5 °C... so a − b = −0.5, on b's denser grid
  // 0.5..12 s. Both linear, so interpolation is exact; a's times inside the
  // overlap [0.5, 10] are 1..10: 10 points.
  std::vector<double> ta, ya, tb, yb;
  for (int i = 0; i <= 10; ++i) {
    ta.push_back(i);
    ya.push_back(50.0 - 2.0 * i);
  }
  for (int i = 1; i <= 24; ++i) {
    tb.push_back(0.5 * i);
    yb.push_back(50.5 - 2.0 * 0.5 * i);
  }
  const auto s = compare_series(series(0, ta, ya), series(0, tb, yb));
  ASSERT_TRUE(s);
  EXPECT_EQ(s->common_points, 10u);
  EXPECT_NEAR(s->bias_c, -0.5, 1e-12);
  EXPECT_NEAR(s->rms_difference_c, 0.5, 1e-12);
  EXPECT_NEAR(s->difference_std_c, 0.0, 1e-12);
  EXPECT_NEAR(s->limits_of_agreement_low_c, -0.5, 1e-9);
  EXPECT_NEAR(s->limits_of_agreement_high_c, -0.5, 1e-9);
  EXPECT_DOUBLE_EQ(s->overlap_start_s, 0.5);
  EXPECT_DOUBLE_EQ(s->overlap_end_s, 10.0);
}

TEST(Agreement, AlternatingDifferencesGiveKnownLimitsOfAgreement) {
  // a − b = ±0.2 alternating on 20 common times: bias 0, RMS 0.2, sd =
  // 0.2·sqrt(20/19), limits ±1.95996·sd.
  std::vector<double> t, ya, yb;
  for (int i = 0; i < 20; ++i) {
    t.push_back(i);
    ya.push_back(30.0);
    yb.push_back(30.0 + (i % 2 ? 0.2 : -0.2));
  }
  const auto s = compare_series(series(0, t, ya), series(0, t, yb));
  ASSERT_TRUE(s);
  const double sd = 0.2 * std::sqrt(20.0 / 19.0);
  EXPECT_NEAR(s->bias_c, 0.0, 1e-12);
  EXPECT_NEAR(s->rms_difference_c, 0.2, 1e-12);
  EXPECT_NEAR(s->difference_std_c, sd, 1e-12);
  EXPECT_NEAR(s->limits_of_agreement_high_c, 1.959964 * sd, 1e-6);
  EXPECT_NEAR(s->limits_of_agreement_low_c, -1.959964 * sd, 1e-6);
}

TEST(Agreement, DifferentOriginsAreAlignedInAbsoluteTime) {
  // The same absolute samples, stored relative to origins 5 s apart.
  std::vector<double> t, y;
  for (int i = 0; i < 30; ++i) {
    t.push_back(i);
    y.push_back(40.0 - 0.5 * i);
  }
  std::vector<double> shifted = t;
  for (double& v : shifted) v -= 5.0;
  const auto s = compare_series(series(1000.0, t, y), series(1005.0, shifted, y));
  ASSERT_TRUE(s);
  EXPECT_EQ(s->common_points, 30u);
  EXPECT_NEAR(s->rms_difference_c, 0.0, 1e-12);
  // Compared without regard to origin they would differ by 2.5 °C.
  const auto wrong = compare_series(series(0.0, t, y), series(0.0, shifted, y));
  ASSERT_TRUE(wrong);
  EXPECT_NEAR(wrong->bias_c, 2.5, 1e-12);
}

TEST(Agreement, DisjointSeriesHaveNoSeriesStatistics) {
  EXPECT_FALSE(compare_series(series(0, {0, 1, 2}, {1, 2, 3}), series(0, {5, 6, 7}, {1, 2, 3})));
}

TEST(Agreement, TwoFitsOfOneCurveAgreeEndToEnd) {
  const testing::CoolingCurve curve{21.0, 75.0, 0.008};
  const auto tc = testing::sample_cooling(curve, 600, 1.0, 0.05, 31);
  const auto bos = testing::sample_cooling(curve, 120, 5.0, 0.3, 32);  // fewer, noisier frames
  const auto tc_series = clean_series(tc.time_s, tc.temperature_c);
  const auto bos_series = clean_series(bos.time_s, bos.temperature_c);
  const auto result = compare_fits(fit_newton(tc_series), fit_newton(bos_series), tc_series, bos_series);
  ASSERT_TRUE(result.k);
  EXPECT_TRUE(result.k->agree) << result.brief_report();
  ASSERT_TRUE(result.series);
  EXPECT_NEAR(result.series->bias_c, 0.0, 0.1);
  EXPECT_NEAR(result.series->difference_std_c, 0.3, 0.06);  // the noisier sensor dominates
  EXPECT_NE(result.brief_report().find("RMS difference"), std::string::npos);
}

}  // namespace
}  // namespace bosfuse::fitting
