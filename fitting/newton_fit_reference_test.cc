// Cross-check against an independent implementation: scipy's curve_fit on
// the fixed data set testdata/newton_reference.csv, computed once by
// testdata/scipy_reference.py and stored in newton_reference_scipy.json.
//
// Tolerances: parameter values to 1e-8 relative and standard errors to
// 1e-7 relative. Both sides stop at tight tolerances near the same minimum
// and both errors are sqrt(diag((JᵀJ)⁻¹)·s²) there; Ceres reaches k through
// log τ and T0 through ΔT, and the covariance maps exactly through the
// reparameterisation's Jacobian at the optimum. Measured differences
// (2026-11-23, scipy 1.10.1): values ≤ 1.5e-10, errors ≤ 2.1e-10 relative,
// so the tolerances leave ~100× room for other compilers and BLAS.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "fitting/newton_fit.h"

namespace bosfuse::fitting {
namespace {

constexpr double kValueTolerance = 1e-8;
constexpr double kErrorTolerance = 1e-7;

const std::string kTestData = std::string(BOSFUSE_SOURCE_DIR) + "/fitting/testdata/";

struct Data {
  std::vector<double> time_s;
  std::vector<double> temperature_c;
};

Data read_reference_csv() {
  std::ifstream in(kTestData + "newton_reference.csv");
  EXPECT_TRUE(in) << "missing " << kTestData << "newton_reference.csv";
  Data data;
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,T_c");
  for (int guard = 0; guard < 100000 && std::getline(in, line); ++guard) {
    const auto comma = line.find(',');
    data.time_s.push_back(std::stod(line.substr(0, comma)));
    data.temperature_c.push_back(std::stod(line.substr(comma + 1)));
  }
  return data;
}

nlohmann::json read_scipy_json() {
  std::ifstream in(kTestData + "newton_reference_scipy.json");
  EXPECT_TRUE(in) << "missing " << kTestData << "newton_reference_scipy.json";
  return nlohmann::json::parse(in);
}

void expect_matches(const Estimate& ours, const nlohmann::json& theirs, const char* name) {
  const double value = theirs.at("value");
  const double error = theirs.at("std_error");
  EXPECT_NEAR(ours.value, value, kValueTolerance * std::abs(value)) << name;
  EXPECT_NEAR(ours.std_error, error, kErrorTolerance * error) << name;
}

class ScipyReference : public ::testing::Test {
 protected:
  Data data_ = read_reference_csv();
  nlohmann::json scipy_ = read_scipy_json();
  NewtonFit fit(const NewtonFitOptions& options) { return fit_newton(data_.time_s, data_.temperature_c, options); }
};

TEST_F(ScipyReference, TheDataSetIsTheOneScipyFitted) {
  EXPECT_EQ(data_.time_s.size(), scipy_.at("points").get<std::size_t>());
}

TEST_F(ScipyReference, FreeAmbientWithScaledErrorsMatchesCurveFit) {
  const auto result = fit({});
  ASSERT_TRUE(result.ok()) << result.brief_report();
  const auto& free = scipy_.at("free");
  expect_matches(result.k_per_s, free.at("k_per_s"), "k");
  expect_matches(result.t0_c, free.at("t0_c"), "T0");
  expect_matches(result.ambient_c, free.at("ambient_c"), "T_amb");
  EXPECT_NEAR(result.summary.residual_rms_c, free.at("residual_rms_c").get<double>(), 1e-9);
}

TEST_F(ScipyReference, FixedAmbientMatchesCurveFit) {
  NewtonFitOptions options;
  options.ambient = AmbientModel::fixed(scipy_.at("fixed_ambient_c"));
  const auto result = fit(options);
  ASSERT_TRUE(result.ok()) << result.brief_report();
  const auto& fixed = scipy_.at("fixed_ambient");
  expect_matches(result.k_per_s, fixed.at("k_per_s"), "k");
  expect_matches(result.t0_c, fixed.at("t0_c"), "T0");
}

TEST_F(ScipyReference, KnownSigmaMatchesCurveFitWithAbsoluteSigma) {
  NewtonFitOptions options;
  options.measurement_sigma_c = scipy_.at("known_sigma_c").get<double>();
  const auto result = fit(options);
  ASSERT_TRUE(result.ok()) << result.brief_report();
  const auto& absolute = scipy_.at("absolute_sigma");
  expect_matches(result.k_per_s, absolute.at("k_per_s"), "k");
  expect_matches(result.t0_c, absolute.at("t0_c"), "T0");
  expect_matches(result.ambient_c, absolute.at("ambient_c"), "T_amb");
}

}  // namespace
}  // namespace bosfuse::fitting
