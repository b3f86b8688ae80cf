// The JSON layout of fits and agreements read back by its own readers:
// every number written comes back, so the report shows what `process`
// stored (a reader once looked for keys the writer never wrote, and the
// report showed NaN limits of agreement and residual RMS).

#include "fitting/fit_json.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

void expect_same(const Estimate& a, const Estimate& b, const char* what) {
  EXPECT_DOUBLE_EQ(a.value, b.value) << what;
  EXPECT_DOUBLE_EQ(a.std_error, b.std_error) << what;
  EXPECT_DOUBLE_EQ(a.low, b.low) << what;
  EXPECT_DOUBLE_EQ(a.high, b.high) << what;
  EXPECT_EQ(a.fixed, b.fixed) << what;
}

NewtonFit a_fit(unsigned seed, double start_s = 0.0) {
  const auto r = testing::sample_cooling(testing::CoolingCurve{}, 300, 1.0, 0.05, seed, start_s);
  return fit_newton(r.time_s, r.temperature_c);
}

TEST(FitJson, AFitComesBackWithEveryNumber) {
  const NewtonFit written = a_fit(3, 12.5);
  ASSERT_TRUE(written.ok());
  const NewtonFit read = fit_from_json(nlohmann::json::parse(to_json(written).dump()));
  EXPECT_TRUE(read.ok());
  EXPECT_DOUBLE_EQ(read.origin_s, written.origin_s);
  EXPECT_DOUBLE_EQ(read.duration_s, written.duration_s);
  expect_same(read.k_per_s, written.k_per_s, "k");
  expect_same(read.tau_s, written.tau_s, "tau");
  expect_same(read.t0_c, written.t0_c, "T0");
  expect_same(read.ambient_c, written.ambient_c, "T_amb");
  const auto& r = read.summary;
  const auto& w = written.summary;
  EXPECT_EQ(r.points_used, w.points_used);
  EXPECT_EQ(r.parameters, w.parameters);
  EXPECT_DOUBLE_EQ(r.dof, w.dof);
  EXPECT_EQ(r.iterations, w.iterations);
  EXPECT_EQ(r.absolute_sigma, w.absolute_sigma);
  EXPECT_DOUBLE_EQ(r.residual_rms_c, w.residual_rms_c);
  EXPECT_DOUBLE_EQ(r.residual_std_c, w.residual_std_c);
  EXPECT_DOUBLE_EQ(r.lag1_autocorrelation, w.lag1_autocorrelation);
  EXPECT_DOUBLE_EQ(r.record_time_constants, w.record_time_constants);
  EXPECT_DOUBLE_EQ(r.confidence, w.confidence);
  EXPECT_EQ(r.warnings, w.warnings);
}

TEST(FitJson, TheCovarianceAndTheCurvesBandComeBack) {
  const NewtonFit written = a_fit(5, 40.0);
  ASSERT_TRUE(written.ok() && written.covariance);
  const auto j = to_json(written);
  ASSERT_TRUE(j.contains("covariance"));
  EXPECT_EQ(j["covariance"]["parameters"], nlohmann::ordered_json({"log_tau", "delta_c", "ambient_c"}));
  const std::string text = j.dump();
  EXPECT_EQ(text.find("null"), std::string::npos) << "an ok fit has a number wherever one belongs";
  const NewtonFit read = fit_from_json(nlohmann::json::parse(text));
  ASSERT_TRUE(read.covariance);
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c) EXPECT_DOUBLE_EQ((*read.covariance)[r][c], (*written.covariance)[r][c]);
  EXPECT_DOUBLE_EQ(read.summary.t_critical, written.summary.t_critical);
  for (double t_s : {40.0, 100.0, 339.0}) {
    EXPECT_DOUBLE_EQ(read.temperature_half_width_at(t_s), written.temperature_half_width_at(t_s)) << t_s;
  }
}

// Fits stored before the covariance and t_critical were written still read:
// no band (no covariance), and t_critical from the dof and confidence.
TEST(FitJson, AnOlderFitWithoutACovarianceStillReads) {
  const NewtonFit written = a_fit(6);
  auto j = nlohmann::json::parse(to_json(written).dump());
  j.erase("covariance");
  j["diagnostics"].erase("t_critical");
  const NewtonFit read = fit_from_json(j);
  EXPECT_TRUE(read.ok());
  EXPECT_FALSE(read.covariance);
  EXPECT_TRUE(std::isnan(read.temperature_half_width_at(10.0)));
  EXPECT_NEAR(read.summary.t_critical, written.summary.t_critical, 1e-9);
  EXPECT_DOUBLE_EQ(read.k_per_s.value, written.k_per_s.value);
}

// A fit whose origin lies too far from its data states T0 at the first
// sample; that comes back, and with it the same curve and band.
TEST(FitJson, WhereT0IsStatedComesBackWithTheSameCurveAndBand) {
  const auto r = testing::sample_cooling(testing::CoolingCurve{}, 300, 1.0, 0.05, 9, 5000.0);
  NewtonFitOptions options;
  options.origin_s = 0.0;
  const NewtonFit written = fit_newton(r.time_s, r.temperature_c, options);
  ASSERT_TRUE(written.ok() && !written.t0_at_origin()) << written.brief_report();
  const auto j = to_json(written);
  EXPECT_EQ(j["t0_reference_s"], 5000.0);
  EXPECT_EQ(j["t0_at_origin"], false);
  const NewtonFit read = fit_from_json(nlohmann::json::parse(j.dump()));
  EXPECT_EQ(read.t0_reference_s, written.t0_reference_s);
  for (double t_s : {5000.0, 5100.0, 5299.0}) {
    EXPECT_DOUBLE_EQ(read.temperature_at(t_s), written.temperature_at(t_s)) << t_s;
    EXPECT_DOUBLE_EQ(read.temperature_half_width_at(t_s), written.temperature_half_width_at(t_s)) << t_s;
  }
  const auto at_origin = to_json(a_fit(9));
  EXPECT_EQ(at_origin["t0_reference_s"], 0.0);
  EXPECT_EQ(at_origin["t0_at_origin"], true);
}

// Fits stored before T0 could be stated elsewhere have it at their origin.
TEST(FitJson, AnOlderFitWithoutAT0ReferenceHasT0AtItsOrigin) {
  const NewtonFit written = a_fit(10, 30.0);
  auto j = nlohmann::json::parse(to_json(written).dump());
  j.erase("t0_reference_s");
  j.erase("t0_at_origin");
  const NewtonFit read = fit_from_json(j);
  EXPECT_TRUE(read.t0_at_origin());
  EXPECT_DOUBLE_EQ(read.temperature_at(30.0), written.t0_c.value);
  EXPECT_DOUBLE_EQ(read.temperature_half_width_at(130.0), written.temperature_half_width_at(130.0));
}

TEST(FitJson, AFixedAmbientsCovarianceKeepsItsZeroRow) {
  const auto r = testing::sample_cooling(testing::CoolingCurve{}, 300, 1.0, 0.05, 8, 0.0);
  NewtonFitOptions options;
  options.ambient = AmbientModel::fixed(22.0);
  const NewtonFit read =
      fit_from_json(nlohmann::json::parse(to_json(fit_newton(r.time_s, r.temperature_c, options)).dump()));
  ASSERT_TRUE(read.covariance);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ((*read.covariance)[2][i], 0.0);
  EXPECT_GT(read.temperature_half_width_at(30.0), 0.0);
}

TEST(FitJson, ReducedChiSquareComesBackOnlyWhereItApplies) {
  const auto r = testing::sample_cooling(testing::CoolingCurve{}, 300, 1.0, 0.05, 4, 0.0);
  NewtonFitOptions known_sigma;
  known_sigma.measurement_sigma_c = 0.05;
  const NewtonFit with = fit_newton(r.time_s, r.temperature_c, known_sigma);
  ASSERT_TRUE(with.summary.reduced_chi_square);
  const NewtonFit read = fit_from_json(nlohmann::json::parse(to_json(with).dump()));
  ASSERT_TRUE(read.summary.reduced_chi_square);
  EXPECT_DOUBLE_EQ(*read.summary.reduced_chi_square, *with.summary.reduced_chi_square);
  EXPECT_TRUE(read.summary.absolute_sigma);
  const auto scaled = to_json(fit_newton(r.time_s, r.temperature_c));
  EXPECT_FALSE(scaled["diagnostics"].contains("reduced_chi_square")) << "absent, not null, where it does not apply";
}

TEST(FitJson, AFailedFitComesBackFailedWithItsReason) {
  const std::vector<double> t = {0, 1, 2};
  const std::vector<double> c = {50, 45, 41};
  const NewtonFit written = fit_newton(t, c);
  ASSERT_FALSE(written.ok());
  const NewtonFit read = fit_from_json(nlohmann::json::parse(to_json(written).dump()));
  EXPECT_EQ(read.summary.status, written.summary.status);
  EXPECT_EQ(read.summary.message, written.summary.message);
  EXPECT_TRUE(std::isnan(read.k_per_s.value));
  EXPECT_FALSE(to_json(written).contains("covariance")) << "absent, not null";
  EXPECT_FALSE(read.covariance);
}

TEST(FitJson, AnAgreementComesBackWithItsLimitsAndOverlap) {
  const NewtonFit a = a_fit(1);
  const NewtonFit b = a_fit(2);
  CleanSeries sa, sb;
  sa.time_s = sb.time_s = {0, 1, 2, 3, 4, 5};
  sa.temperature_c = {50, 48, 46, 44, 42, 40};
  sb.temperature_c = {50.2, 47.9, 46.3, 43.8, 42.1, 40.2};
  const Agreement written = compare_fits(a, b, sa, sb);
  ASSERT_TRUE(written.k && written.series);
  const Agreement read = agreement_from_json(nlohmann::json::parse(to_json(written).dump()));
  EXPECT_EQ(read.verdict, written.verdict);
  ASSERT_TRUE(read.k && read.series);
  EXPECT_DOUBLE_EQ(read.k->z, written.k->z);
  EXPECT_EQ(read.k->agree, written.k->agree);
  const auto& r = *read.series;
  const auto& w = *written.series;
  EXPECT_EQ(r.common_points, w.common_points);
  EXPECT_DOUBLE_EQ(r.overlap_start_s, w.overlap_start_s);
  EXPECT_DOUBLE_EQ(r.overlap_end_s, w.overlap_end_s);
  EXPECT_GT(r.overlap_end_s, r.overlap_start_s);
  EXPECT_DOUBLE_EQ(r.bias_c, w.bias_c);
  EXPECT_DOUBLE_EQ(r.limits_of_agreement_low_c, w.limits_of_agreement_low_c);
  EXPECT_DOUBLE_EQ(r.limits_of_agreement_high_c, w.limits_of_agreement_high_c);
  EXPECT_TRUE(std::isfinite(r.limits_of_agreement_low_c));
}

// The random and systematic parts of each parameter's σ come back; an
// agreement stored without them reads as all random.
TEST(FitJson, AnAgreementKeepsTheRandomAndSystematicParts) {
  AgreementOptions options;
  options.b_systematic = {1e-5, 1.5, 0.7};
  const Agreement written = compare_fits(a_fit(1), a_fit(2), {}, {}, options);
  ASSERT_TRUE(written.curve);
  nlohmann::json j = nlohmann::json::parse(to_json(written).dump());
  const Agreement read = agreement_from_json(j);
  ASSERT_TRUE(read.curve);
  for (std::size_t i = 0; i < written.curve->parameters.size(); ++i) {
    EXPECT_DOUBLE_EQ(read.curve->parameters[i].random_std_error, written.curve->parameters[i].random_std_error);
    EXPECT_DOUBLE_EQ(read.curve->parameters[i].systematic_std_error,
                     written.curve->parameters[i].systematic_std_error);
  }
  EXPECT_DOUBLE_EQ(read.curve->parameters[1].systematic_std_error, 1.5);
  for (auto& p : j.at("equivalence").at("parameters")) {
    p.erase("random_std_error");
    p.erase("systematic_std_error");
  }
  const Agreement old = agreement_from_json(j);
  EXPECT_DOUBLE_EQ(old.curve->parameters[1].random_std_error, old.curve->parameters[1].std_error);
  EXPECT_EQ(old.curve->parameters[1].systematic_std_error, 0.0);
}

TEST(FitJson, AnAgreementKeepsItsOldKeysAndAddsTheEquivalenceTestAndTheLag) {
  const NewtonFit a = a_fit(1);
  const NewtonFit b = a_fit(2);
  CleanSeries sa, sb;
  sa.time_s = sb.time_s = {0, 1, 2, 3, 4, 5};
  sa.temperature_c = {50, 48, 46, 44, 42, 40};
  sb.temperature_c = {50.2, 47.9, 46.3, 43.8, 42.1, 40.2};
  AgreementOptions options;
  options.a_time_constant_s = 0.5;
  const Agreement written = compare_fits(a, b, sa, sb, options);
  ASSERT_TRUE(written.curve && written.series);
  const nlohmann::json j = nlohmann::json::parse(to_json(written).dump());
  for (const char* key : {"verdict", "k", "series", "confidence", "equivalence", "lag"})
    EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key :
       {"rms_difference_c", "common_points", "bias_c", "rms_difference_as_read_c", "bias_as_read_c"}) {
    EXPECT_TRUE(j["series"].contains(key)) << key;
  }
  EXPECT_EQ(j["equivalence"]["verdict"], to_string(written.curve->verdict));
  EXPECT_EQ(j["equivalence"]["parameters"].size(), 3u);
  EXPECT_EQ(j["lag"]["source"], "given");
  const Agreement read = agreement_from_json(j);
  ASSERT_TRUE(read.curve);
  EXPECT_EQ(read.curve->verdict, written.curve->verdict);
  EXPECT_EQ(read.curve->deciding_parameter, written.curve->deciding_parameter);
  ASSERT_EQ(read.curve->parameters.size(), written.curve->parameters.size());
  for (std::size_t i = 0; i < read.curve->parameters.size(); ++i) {
    const auto &r = read.curve->parameters[i], &w = written.curve->parameters[i];
    EXPECT_EQ(r.name, w.name);
    EXPECT_DOUBLE_EQ(r.z, w.z);
    EXPECT_DOUBLE_EQ(r.margin, w.margin);
    EXPECT_DOUBLE_EQ(r.interval_low, w.interval_low);
    EXPECT_EQ(r.verdict, w.verdict);
    EXPECT_EQ(r.in_verdict, w.in_verdict);
  }
  EXPECT_EQ(read.lag.source, "given");
  EXPECT_DOUBLE_EQ(read.lag.time_constant_s, 0.5);
  EXPECT_DOUBLE_EQ(read.series->rms_difference_as_read_c, written.series->rms_difference_as_read_c);
}

TEST(FitJson, AnAgreementStoredBeforeTheEquivalenceTestReadsWithoutOne) {
  const auto j = nlohmann::json::parse(R"({"verdict": "k agree within uncertainty.", "k": null,
      "series": {"common_points": 5, "rms_difference_c": 0.2, "bias_c": 0.1}})");
  const Agreement read = agreement_from_json(j);
  EXPECT_FALSE(read.curve);
  EXPECT_EQ(read.lag.source, "none");
  ASSERT_TRUE(read.series);
  EXPECT_DOUBLE_EQ(read.series->rms_difference_as_read_c, 0.2);
  EXPECT_THROW(agreement_from_json(nlohmann::json::parse(R"({"equivalence": {"verdict": "maybe", "parameters": []}})")),
               nlohmann::json::exception);
}

}  // namespace
}  // namespace bosfuse::fitting
