#include "fusion/calibration.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace bosfuse::fusion {
namespace {

struct Data {
  std::vector<double> x, y;
};

Data line(double slope, double intercept, double noise_c, unsigned seed, int n = 30) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0, noise_c);
  Data d;
  for (int i = 0; i < n; ++i) {
    d.x.push_back(0.05 + 0.02 * i);  // shifts of 0.05..0.63 px
    d.y.push_back(intercept + slope * d.x.back() + noise(random));
  }
  return d;
}

TEST(Calibration, ThroughTheOriginRecoversTheSlopeWithAnHonestUncertainty) {
  const Data d = line(25, 0, 0.2, 1);
  const auto c = fit_linear_calibration(d.x, d.y);
  ASSERT_TRUE(c.ok) << c.message;
  double sxx = 0;
  for (double x : d.x) sxx += x * x;
  EXPECT_NEAR(c.slope, 25, 3 * 0.2 / std::sqrt(sxx));
  EXPECT_NEAR(c.slope_std_error, 0.2 / std::sqrt(sxx), 0.3 * 0.2 / std::sqrt(sxx));
  EXPECT_NEAR(c.residual_rms, 0.2, 0.07);
  EXPECT_EQ(c.intercept, 0);
  EXPECT_NE(c.brief_report().find("degC per unit"), std::string::npos);
}

// 400 seeds: the ±t·SE interval (Student t, 29 dof, 95%: 2.045) covers the
// true slope 96.0% of the time (measured; binomial σ at 95% is 1.1%).
TEST(Calibration, IntervalCoverageIsCloseToNominal) {
  int covered = 0;
  const int seeds = 400;
  for (int seed = 0; seed < seeds; ++seed) {
    const Data d = line(25, 0, 0.2, static_cast<unsigned>(seed) + 100);
    const auto c = fit_linear_calibration(d.x, d.y);
    ASSERT_TRUE(c.ok);
    covered += std::abs(c.slope - 25) <= 2.045 * c.slope_std_error ? 1 : 0;
  }
  const double coverage = static_cast<double>(covered) / seeds;
  RecordProperty("coverage", std::to_string(coverage));
  std::printf("calibration slope interval coverage: %.3f\n", coverage);
  EXPECT_GT(coverage, 0.91);
  EXPECT_LT(coverage, 0.98);
}

TEST(Calibration, WithAnInterceptAndWeights) {
  const Data d = line(-12, 1.5, 0.05, 3);
  std::vector<double> w(d.x.size(), 4.0);
  CalibrationOptions options;
  options.through_origin = false;
  const auto c = fit_linear_calibration(d.x, d.y, w, options);
  ASSERT_TRUE(c.ok) << c.message;
  EXPECT_NEAR(c.slope, -12, 4 * c.slope_std_error);
  EXPECT_NEAR(c.intercept, 1.5, 4 * c.intercept_std_error);
  EXPECT_GT(c.intercept_std_error, 0);
}

TEST(Calibration, NonFiniteAndDegenerateInputsAreReported) {
  Data d = line(25, 0, 0.1, 5, 10);
  d.x[2] = NAN;
  d.y[4] = INFINITY;
  const auto c = fit_linear_calibration(d.x, d.y);
  EXPECT_TRUE(c.ok);
  EXPECT_EQ(c.rejected_non_finite, 2u);
  EXPECT_EQ(c.points, 8u);
  const std::vector<double> zeros(5, 0.0), ys(5, 1.0);
  const auto flat = fit_linear_calibration(zeros, ys);
  EXPECT_FALSE(flat.ok);
  EXPECT_NE(flat.message.find("does not vary"), std::string::npos);
  const auto few = fit_linear_calibration(std::vector<double>{1.0}, std::vector<double>{2.0});
  EXPECT_FALSE(few.ok);
  EXPECT_THROW(fit_linear_calibration(zeros, std::vector<double>{1.0}), std::invalid_argument);
}

bool names(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& p : problems) {
    if (p.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(CalibrationChecks, AGoodCalibrationPassesAndR2IsAboutTheMean) {
  const Data d = line(25, 0, 0.2, 1);
  const auto c = fit_linear_calibration(d.x, d.y);
  EXPECT_GT(c.r2, 0.95);
  EXPECT_TRUE(calibration_problems(c, shift_uncertainty({}, {}), {}).empty());
}

// The centreline case: the thermocouple cools by 28 degC below its
// reading at the reference frame while BOS sees 0.02..0.08 px of noise.
TEST(CalibrationChecks, TheCentrelineCaseFailsNamingItsSlopeResidualAndShiftRange) {
  std::mt19937 random(2);
  std::uniform_real_distribution<double> shift(0.02, 0.08);
  Data d;
  for (int i = 0; i < 23; ++i) {
    d.x.push_back(shift(random));
    d.y.push_back(-28 * (1 - std::exp(-0.006 * 10 * i)));
  }
  const auto c = fit_linear_calibration(d.x, d.y);
  ASSERT_TRUE(c.ok) << c.message;
  const auto problems = calibration_problems(c, shift_uncertainty({}, {}), {});
  for (const auto& p : problems) std::printf("%s\n", p.c_str());
  ASSERT_EQ(problems.size(), 4u) << "sign, r2, residual and shift range";
  EXPECT_TRUE(names(problems, fmt::format("the slope {:.4g} degC/px has the wrong sign", c.slope)));
  EXPECT_TRUE(names(problems, "a slope > 0 is expected"));
  EXPECT_TRUE(names(problems, fmt::format("residual RMS {:.3g} degC", c.residual_rms)));
  EXPECT_TRUE(names(problems, fmt::format("r2 = {:.3g}", c.r2)));
  EXPECT_TRUE(names(problems, fmt::format("BOS sees no shift where this thermocouple is: the shift ranges over "
                                          "{:.3g}..{:.3g} px",
                                          c.x_min, c.x_max)));
  EXPECT_TRUE(names(problems, "uncertainty 0.05 px (the default noise floor"));
  CalibrationChecks cooled;
  cooled.expected_sign = -1;
  EXPECT_FALSE(names(calibration_problems(c, shift_uncertainty({}, cooled), cooled), "wrong sign"))
      << "a flow colder than the reference's air has a negative slope";
}

TEST(CalibrationChecks, TooFewPointsAndAShiftRangeBelowTheProbesSigma) {
  const Data d = line(25, 0, 0.01, 3, 4);  // shifts 0.05..0.11 px
  const auto c = fit_linear_calibration(d.x, d.y);
  ASSERT_TRUE(c.ok);
  const std::vector<double> sigma{0.0, 0.01, 0.02, 0.015, NAN};  // 0: not estimated
  const auto shift = shift_uncertainty(sigma, {});
  EXPECT_DOUBLE_EQ(shift.sigma_px, 0.015);
  EXPECT_NE(shift.source.find("median sigma over 3 samples"), std::string::npos) << shift.source;
  auto problems = calibration_problems(c, shift, {});
  EXPECT_TRUE(names(problems, "too few points: 4, at least 5 needed"));
  EXPECT_FALSE(names(problems, "BOS sees no shift")) << "0.06 px spans 3 x 0.015 px";
  CalibrationChecks strict;
  strict.min_shift_range_sigmas = 5;
  problems = calibration_problems(c, shift, strict);
  EXPECT_TRUE(names(problems, "less than 5 x the shift's uncertainty 0.015 px (the probe's median sigma"));
  strict.min_r2 = 2;
  EXPECT_THROW(calibration_problems(c, shift, strict), std::invalid_argument);
  LinearCalibration failed;
  failed.message = "2 usable points, at least 3 needed";
  EXPECT_EQ(calibration_problems(failed, shift, {}), std::vector<std::string>{failed.message});
}

}  // namespace
}  // namespace bosfuse::fusion
