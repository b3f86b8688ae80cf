// Agreement of two fits and two series, on cases with known answers.

#include "fitting/agreement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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
  // Δk's 95% interval ±0.00098 reaches past the 5% margin (±0.00051): too uncertain to tell.
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kInconclusive);
  EXPECT_EQ(result.verdict.rfind("Inconclusive: the uncertainty of k is too large", 0), 0u) << result.verdict;
  EXPECT_FALSE(result.series);
  EXPECT_NE(result.verdict.find("too few common times"), std::string::npos);
}

TEST(Agreement, KFurtherApartThanTheirUncertaintiesDiffer) {
  // Δk = −0.002, combined σ = 0.0001·√2: z = −14.14; 18.2% of the mean.
  const auto result = compare_fits(fit_with_k(0.010, 0.0001), fit_with_k(0.012, 0.0001), {}, {});
  ASSERT_TRUE(result.k);
  EXPECT_NEAR(result.k->z, -0.002 / (0.0001 * std::sqrt(2.0)), 1e-6);
  EXPECT_FALSE(result.k->agree);
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kDiffer);
  EXPECT_EQ(result.curve->deciding_parameter, "k_per_s");
  EXPECT_EQ(result.verdict.rfind("Differ: k of", 0), 0u) << result.verdict;
  EXPECT_NE(result.verdict.find("k differ (Δ = -0.002 ± 0.00014 1/s, z = -14.14, margin ±0.00055 1/s)"),
            std::string::npos)
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
  // 0.5..12 s. Both linear, so interpolation is exact; the pairs are at b's
  // times inside the overlap [0.5, 10], 0.5..10: 20 points.
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
  EXPECT_EQ(s->common_points, 20u);
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
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kAgree) << result.brief_report();
  EXPECT_EQ(result.verdict.rfind("Agree: the whole curve (k, T0, T_amb)", 0), 0u) << result.verdict;
  EXPECT_NE(result.lag.source, "estimated") << "noise alone is not a lag: " << result.brief_report();
}

// A sensor with a first-order lag τ whose start-up transient has died out
// (the record begins several τ after the cooling did): the amplitude over
// (1 − kτ). The transient itself is not modelled (docs/FITTING.md).
std::vector<double> lagged_readings(const testing::CoolingCurve& c, const std::vector<double>& t, double tau_s,
                                    double noise_c, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, noise_c);
  std::vector<double> y;
  for (double ti : t) {
    const double shape = std::exp(-c.k_per_s * ti) / (1.0 - c.k_per_s * tau_s);
    y.push_back(c.ambient_c + (c.t0_c - c.ambient_c) * shape + noise(random));
  }
  return y;
}

// The demo's case in small: a thermocouple at 1 Hz with a 5 s lag, BOS
// frames every 10 s without one.
struct LaggedPair {
  CleanSeries tc, bos;
  NewtonFit tc_fit, bos_fit;
};

LaggedPair lagged_pair(double tau_s, double bos_noise_c, double bos_k_factor = 1.0, unsigned seed = 41) {
  const testing::CoolingCurve curve{22.0, 80.0, 0.01};
  std::vector<double> t;
  for (int i = 0; i <= 400; ++i) t.push_back(i);
  LaggedPair p;
  p.tc = clean_series(t, lagged_readings(curve, t, tau_s, 0.05, seed), 0.0);
  testing::CoolingCurve seen = curve;
  seen.k_per_s *= bos_k_factor;
  const auto bos = testing::sample_cooling(seen, 40, 10.0, bos_noise_c, seed + 1);
  p.bos = clean_series(bos.time_s, bos.temperature_c, 0.0);
  p.tc_fit = fit_newton(p.tc);
  p.bos_fit = fit_newton(p.bos);
  return p;
}

TEST(Agreement, BlandAltmanPairsAtTheBosFrames) {
  const LaggedPair p = lagged_pair(0.0, 0.1);
  const auto result = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos);
  ASSERT_TRUE(result.series);
  EXPECT_EQ(result.series->common_points, 40u) << "one pair per BOS frame, not per thermocouple sample";
  EXPECT_NE(result.verdict.find("On 40 BOS frame times"), std::string::npos) << result.verdict;
  EXPECT_NE(result.brief_report().find("Bland–Altman n = 40"), std::string::npos) << result.brief_report();
}

TEST(Agreement, AGivenLagIsRemovedNotReportedAsDisagreement) {
  const LaggedPair p = lagged_pair(5.0, 0.1);  // kτ = 0.05: the thermocouple reads 5% of ΔT warm
  AgreementOptions ignore_lag;
  ignore_lag.estimate_lag = false;
  const auto as_read = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos, ignore_lag);
  ASSERT_TRUE(as_read.curve);
  EXPECT_EQ(as_read.curve->verdict, Verdict::kDiffer) << as_read.brief_report();
  EXPECT_EQ(as_read.curve->deciding_parameter, "T0_c");
  EXPECT_EQ(as_read.lag.source, "none");

  AgreementOptions given;
  given.a_time_constant_s = 5.0;
  const auto result = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos, given);
  ASSERT_TRUE(result.curve && result.series);
  EXPECT_EQ(result.curve->verdict, Verdict::kAgree) << result.brief_report();
  EXPECT_EQ(result.lag.source, "given");
  EXPECT_DOUBLE_EQ(result.lag.time_constant_s, 5.0);
  // As read, the pairs differ by kτ·(T − T_amb), up to 2.9 °C; de-lagged only by the noise.
  EXPECT_GT(result.series->rms_difference_as_read_c, 1.0);
  EXPECT_LT(result.series->rms_difference_c, 0.2);
  EXPECT_NEAR(result.series->bias_c, 0.0, 0.1);
  EXPECT_NE(result.verdict.find("τ = 5 s (given)"), std::string::npos) << result.verdict;
}

TEST(Agreement, AnUnstatedLagIsEstimatedAndTakesT0OutOfTheVerdict) {
  const LaggedPair p = lagged_pair(5.0, 0.1);
  const auto result = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos);
  ASSERT_EQ(result.lag.source, "estimated") << result.brief_report();
  EXPECT_NEAR(result.lag.time_constant_s, 5.0, std::max(0.5, 3.0 * result.lag.std_error_s));
  EXPECT_GT(result.lag.std_error_s, 0.0);
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kAgree) << result.brief_report();
  for (const auto& parameter : result.curve->parameters) {
    EXPECT_EQ(parameter.in_verdict, parameter.name != "T0_c") << parameter.name;
  }
}

TEST(Agreement, ALargeUncertaintyIsInconclusive) {
  const LaggedPair p = lagged_pair(0.0, 4.0);  // BOS σ 4 °C: k known to about ±10%
  AgreementOptions options;
  options.a_time_constant_s = 0.0;
  const auto result = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos, options);
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kInconclusive) << result.brief_report();
  const ParameterAgreement* d = result.curve->deciding();
  ASSERT_NE(d, nullptr);
  EXPECT_LT(d->interval_low, d->margin);
  EXPECT_GT(d->interval_high, -d->margin);
  EXPECT_EQ(result.verdict.rfind("Inconclusive: the uncertainty of", 0), 0u) << result.verdict;
  // The same curves measured well agree.
  const LaggedPair q = lagged_pair(0.0, 0.1);
  EXPECT_EQ(compare_fits(q.tc_fit, q.bos_fit, q.tc, q.bos, options).curve->verdict, Verdict::kAgree);
}

TEST(Agreement, ARateBeyondItsMarginDiffers) {
  const LaggedPair p = lagged_pair(0.0, 0.1, 1.2);  // BOS sees k 20% faster
  AgreementOptions options;
  options.a_time_constant_s = 0.0;
  const auto result = compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos, options);
  ASSERT_TRUE(result.curve);
  EXPECT_EQ(result.curve->verdict, Verdict::kDiffer) << result.brief_report();
  EXPECT_EQ(result.curve->parameters[0].verdict, Verdict::kDiffer);
  // A margin wider than the difference makes it agree.
  options.margin_k_relative = 0.5;
  options.margin_c = 20;
  EXPECT_EQ(compare_fits(p.tc_fit, p.bos_fit, p.tc, p.bos, options).curve->verdict, Verdict::kAgree);
}

TEST(Agreement, TheCurveTakesTheWorstOfItsParameters) {
  // k agrees (Δk 0 ± 0.00014, margin ±0.0005), T0 differs by 3 °C (± 0.14, margin 1 °C).
  NewtonFit a = fit_with_k(0.010, 0.0001), b = fit_with_k(0.010, 0.0001);
  a.t0_c = {83.0, 0.1, 0, 0, false};
  b.t0_c = {80.0, 0.1, 0, 0, false};
  const auto result = compare_fits(a, b, {}, {});
  ASSERT_TRUE(result.curve);
  ASSERT_EQ(result.curve->parameters.size(), 3u);
  EXPECT_EQ(result.curve->parameters[0].verdict, Verdict::kAgree);
  EXPECT_EQ(result.curve->parameters[1].verdict, Verdict::kDiffer);
  EXPECT_NEAR(result.curve->parameters[1].z, 3.0 / (0.1 * std::sqrt(2.0)), 1e-9);
  EXPECT_DOUBLE_EQ(result.curve->parameters[1].margin, 1.0);
  EXPECT_EQ(result.curve->parameters[2].verdict, Verdict::kAgree);
  EXPECT_EQ(result.curve->verdict, Verdict::kDiffer);
  EXPECT_EQ(result.curve->deciding_parameter, "T0_c");
  EXPECT_NE(result.verdict.find("T0 differ (Δ = 3 ± 0.14 °C, z = 21.21, margin ±1 °C)"), std::string::npos)
      << result.verdict;
}

// T0 3 °C apart with random σ 0.1 each differs; a stated systematic σ of
// 2 °C on the BOS T0 (its set-up's budget through the fit) cannot be
// excluded, so the same curves read inconclusive, and the sentence says the
// systematic part dominates. A small systematic part leaves the verdict.
TEST(Agreement, ALargeSystematicUncertaintyIsInconclusiveNotDiffer) {
  NewtonFit a = fit_with_k(0.010, 0.0001), b = fit_with_k(0.010, 0.0001);
  a.t0_c = {83.0, 0.1, 0, 0, false};
  b.t0_c = {80.0, 0.1, 0, 0, false};
  AgreementOptions options;
  EXPECT_EQ(compare_fits(a, b, {}, {}, options).curve->verdict, Verdict::kDiffer);
  options.b_systematic = {0.0, 2.0, 2.0};
  const auto result = compare_fits(a, b, {}, {}, options);
  ASSERT_TRUE(result.curve);
  const ParameterAgreement& t0 = result.curve->parameters[1];
  EXPECT_NEAR(t0.random_std_error, 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(t0.systematic_std_error, 2.0);
  EXPECT_NEAR(t0.std_error, std::hypot(0.1 * std::sqrt(2.0), 2.0), 1e-12);
  EXPECT_EQ(t0.verdict, Verdict::kInconclusive);
  EXPECT_EQ(result.curve->verdict, Verdict::kInconclusive) << result.verdict;
  EXPECT_EQ(result.curve->deciding_parameter, "T0_c");
  EXPECT_NE(result.verdict.find("the systematic part (the set-up's Type-B budget) dominates"), std::string::npos)
      << result.verdict;
  EXPECT_NE(result.verdict.find("random ± 0.14, systematic ± 2"), std::string::npos) << result.verdict;
  options.b_systematic = {0.0, 0.2, 0.2};
  EXPECT_EQ(compare_fits(a, b, {}, {}, options).curve->verdict, Verdict::kDiffer) << "3 °C is beyond 0.25 °C";
  options.b_systematic.t0_c = -1;
  EXPECT_THROW(compare_fits(a, b, {}, {}, options), std::invalid_argument);
}

TEST(Agreement, AProbeInPixelsIsJudgedOnKAlone) {
  NewtonFit a = fit_with_k(0.010, 0.0001), b = fit_with_k(0.010, 0.0001);
  a.t0_c = {83.0, 0.1, 0, 0, false};
  b.t0_c = {0.4, 0.01, 0, 0, false};  // px
  AgreementOptions options;
  options.b_is_temperature = false;
  const auto result = compare_fits(a, b, {}, {}, options);
  ASSERT_TRUE(result.curve);
  ASSERT_EQ(result.curve->parameters.size(), 1u);
  EXPECT_EQ(result.curve->verdict, Verdict::kAgree);
  EXPECT_EQ(result.verdict.rfind("Agree: k (the probe is not in °C)", 0), 0u) << result.verdict;
  EXPECT_FALSE(result.series);
}

// The verdict is two one-sided tests at α = 0.05 (Schuirmann 1987): T0
// 0.5 ± 0.28 °C apart (σ 0.2 each) against ±1 °C has the 90 % interval
// [0.035, 0.965], inside the margin: equivalent; the 95 % two-sided
// interval [−0.05, 1.05] reaches past it, which is a test at α = 0.025.
// The level is an option, stored with the intervals it made.
TEST(Agreement, TheVerdictIsTwoOneSidedTestsAtTheNinetyPercentInterval) {
  NewtonFit a = fit_with_k(0.010, 0.00001), b = fit_with_k(0.010, 0.00001);
  a.t0_c = {80.5, 0.2, 0, 0, false};
  b.t0_c = {80.0, 0.2, 0, 0, false};
  const auto tost = compare_fits(a, b, {}, {});
  ASSERT_TRUE(tost.curve);
  const ParameterAgreement& t0 = tost.curve->parameters[1];
  EXPECT_DOUBLE_EQ(tost.curve->alpha, 0.05);
  EXPECT_DOUBLE_EQ(tost.curve->confidence, 0.90);
  EXPECT_NEAR(t0.critical, 1.6449, 1e-3) << "one-sided at 0.05";
  EXPECT_NEAR(t0.interval_high, 0.5 + 1.6449 * 0.2 * std::sqrt(2.0), 1e-3);
  EXPECT_EQ(t0.verdict, Verdict::kAgree);
  EXPECT_EQ(tost.curve->verdict, Verdict::kAgree) << tost.verdict;
  EXPECT_NE(tost.verdict.find("90% intervals inside ±margin: two one-sided tests at α = 0.05"), std::string::npos)
      << tost.verdict;
  AgreementOptions two_sided_95;
  two_sided_95.equivalence_alpha = 0.025;
  const auto strict = compare_fits(a, b, {}, {}, two_sided_95);
  EXPECT_EQ(strict.curve->parameters[1].verdict, Verdict::kInconclusive);
  EXPECT_GT(strict.curve->parameters[1].interval_high, 1.0);
  two_sided_95.equivalence_alpha = 0.5;
  EXPECT_NE(two_sided_95.Validate(), "");
}

// A probe fit whose σ were scaled by a Birge ratio estimated from n − p
// residuals carries that dof, and the comparison's critical value is
// Student t at the Welch–Satterthwaite dof it gives, not normal.
TEST(Agreement, AnEstimatedSigmaScaleGivesStudentT) {
  NewtonFit a = fit_with_k(0.010, 0.0001), b = fit_with_k(0.010, 0.0001);
  b.summary.absolute_sigma = true;
  b.summary.interval_dof = 5.0;
  const auto result = compare_fits(a, b, {}, {});
  ASSERT_TRUE(result.curve);
  // Equal variances, a's with infinite dof: (va + vb)² / (vb² / 5) = 20 dof, t one-sided 0.05 = 1.725.
  EXPECT_NEAR(result.curve->parameters[0].critical, 1.7247, 1e-3);
  b.summary.interval_dof.reset();
  EXPECT_NEAR(compare_fits(a, b, {}, {}).curve->parameters[0].critical, 1.645, 1e-3);
}

TEST(Agreement, MarginsMustBePositive) {
  AgreementOptions options;
  options.margin_c = 0;
  EXPECT_NE(options.Validate(), "");
  options.margin_c = 1;
  options.margin_k_relative = -0.1;
  EXPECT_NE(options.Validate(), "");
  options.margin_k_relative = 0.05;
  options.a_time_constant_s = -1;
  EXPECT_NE(options.Validate(), "");
}

}  // namespace
}  // namespace bosfuse::fitting
