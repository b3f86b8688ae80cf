// A first-order sensor lag on Newton cooling curves, against the closed form.

#include "fitting/sensor_lag.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

// The lagged sensor once its start-up transient has gone: the same k and
// T_amb, the amplitude over (1 − kτ).
testing::CoolingCurve lagged_curve(const testing::CoolingCurve& c, double tau_s) {
  return {c.ambient_c, c.ambient_c + (c.t0_c - c.ambient_c) / (1.0 - c.k_per_s * tau_s), c.k_per_s};
}

TEST(SensorLag, DelaggingAFitRestoresTheAmplitudeAndKeepsKAndAmbient) {
  const testing::CoolingCurve truth{22.0, 80.0, 0.01};
  const auto record = testing::sample_cooling(lagged_curve(truth, 4.0), 300, 1.0, 0.05, 3);
  const NewtonFit lagged = fit_newton(record.time_s, record.temperature_c);
  ASSERT_TRUE(lagged.ok());
  const NewtonFit fit = delagged(lagged, 4.0);
  ASSERT_TRUE(fit.ok());
  EXPECT_NEAR(fit.t0_c.value, 80.0, 4 * fit.t0_c.std_error + 0.01);
  EXPECT_GT(lagged.t0_c.value - 80.0, 2.0) << "as read, T0 is 58·0.04/0.96 = 2.4 °C warm";
  EXPECT_DOUBLE_EQ(fit.k_per_s.value, lagged.k_per_s.value);
  EXPECT_DOUBLE_EQ(fit.ambient_c.value, lagged.ambient_c.value);
  // The band follows the curve: the de-lagged fit's band at T0's time is its T0 standard error.
  EXPECT_NEAR(fit.temperature_half_width_at(0.0), fit.summary.t_critical * fit.t0_c.std_error, 1e-9);
  EXPECT_DOUBLE_EQ(fit.temperature_at(0.0), fit.t0_c.value);
}

TEST(SensorLag, DelaggingReadingsAddsTauTimesTheFittedSlope) {
  const testing::CoolingCurve truth{20.0, 70.0, 0.02};
  const auto record = testing::sample_cooling(lagged_curve(truth, 2.0), 200, 1.0, 0.0, 1);
  const auto series = clean_series(record.time_s, record.temperature_c, 0.0);
  const NewtonFit fit = fit_newton(series);
  ASSERT_TRUE(fit.ok());
  const CleanSeries out = delagged(series, fit, 2.0);
  for (std::size_t i = 0; i < out.size(); i += 17) EXPECT_NEAR(out.temperature_c[i], truth.at(out.time_s[i]), 1e-6);
  EXPECT_EQ(delagged(series, fit, 0.0).temperature_c, series.temperature_c);
}

TEST(SensorLag, ALagAsLongAsTheCurveIsFlaggedAndNegativeOnesRefused) {
  const auto record = testing::sample_cooling({22.0, 80.0, 0.01}, 300, 1.0, 0.05, 3);
  const NewtonFit fit = fit_newton(record.time_s, record.temperature_c);
  const NewtonFit broken = delagged(fit, 150.0);  // kτ = 1.5
  EXPECT_FALSE(broken.ok());
  EXPECT_NE(broken.summary.message.find("k·τ ≥ 1"), std::string::npos);
  EXPECT_THROW(delagged(fit, -1.0), std::invalid_argument);
  EXPECT_THROW(delagged(fit, NAN), std::invalid_argument);
}

TEST(SensorLag, TheEstimateRecoversTauFromPairedDifferences) {
  const testing::CoolingCurve truth{22.0, 80.0, 0.01};
  const auto tc = testing::sample_cooling(lagged_curve(truth, 3.0), 400, 1.0, 0.05, 5);
  const auto bos = testing::sample_cooling(truth, 40, 10.0, 0.1, 6);
  const auto tc_series = clean_series(tc.time_s, tc.temperature_c, 0.0);
  const auto bos_series = clean_series(bos.time_s, bos.temperature_c, 0.0);
  const auto estimate = estimate_lag(tc_series, fit_newton(tc_series), bos_series);
  ASSERT_TRUE(estimate);
  EXPECT_EQ(estimate->points, 40u);
  EXPECT_NEAR(estimate->time_constant_s, 3.0, 3 * estimate->std_error_s);
  EXPECT_LT(estimate->std_error_s, 0.5);
  // A constant offset of the reference is the intercept, not a lag.
  CleanSeries offset = bos_series;
  for (double& v : offset.temperature_c) v -= 1.5;
  EXPECT_NEAR(estimate_lag(tc_series, fit_newton(tc_series), offset)->time_constant_s, estimate->time_constant_s, 1e-9);
}

TEST(SensorLag, NoEstimateWithoutEnoughOverlap) {
  const auto tc = testing::sample_cooling({22.0, 80.0, 0.01}, 100, 1.0, 0.05, 5);
  const auto tc_series = clean_series(tc.time_s, tc.temperature_c, 0.0);
  const auto late = testing::sample_cooling({22.0, 80.0, 0.01}, 10, 10.0, 0.1, 6, 500.0);
  EXPECT_FALSE(estimate_lag(tc_series, fit_newton(tc_series), clean_series(late.time_s, late.temperature_c, 0.0)));
}

}  // namespace
}  // namespace bosfuse::fitting
