// The agreement process.cc stores, on the simulator's own thermocouples: the
// first-order lag sim/ gives them (SceneThermocouple::lag_s) is what the
// agreement estimates when the experiment file states none, and, removed,
// is not reported as disagreement with the air the BOS probe sees.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fitting/agreement.h"
#include "fitting/sensor_lag.h"
#include "sim/convection_scene.h"

namespace bosfuse::pipeline {
namespace {

struct SimulatedPair {
  fitting::CleanSeries tc, air;
  fitting::NewtonFit tc_fit, air_fit;
};

// A thermocouple at 1 Hz over 240 s, and the air it sits in every 10 s (what
// a noiseless BOS probe would read), the first 20 s left out so that the
// sensor's start-up transient (FITTING.md) has died out.
SimulatedPair simulated_pair(double lag_s) {
  sim::SceneOptions options;
  options.pure_exponential = true;
  options.duration_s = 300;
  const sim::ConvectionScene scene(options);
  const sim::SceneThermocouple tc{"tc", 0.0, 0.035, lag_s, 0.05};
  std::vector<double> t_tc, t_air, air;
  for (int i = 0; i <= 240; ++i) t_tc.push_back(i);
  const std::vector<double> readings = scene.thermocouple_readings(tc, t_tc, 7);
  std::vector<double> t_kept(t_tc.begin() + 20, t_tc.end()), readings_kept(readings.begin() + 20, readings.end());
  for (int i = 2; i <= 24; ++i) {
    t_air.push_back(10.0 * i);
    air.push_back(scene.temperature_c(0.0, 0.035, 10.0 * i));
  }
  SimulatedPair p;
  p.tc = fitting::clean_series(t_kept, readings_kept, 0.0);
  p.air = fitting::clean_series(t_air, air, 0.0);
  p.tc_fit = fitting::fit_newton(p.tc);
  p.air_fit = fitting::fit_newton(p.air);
  return p;
}

TEST(ProcessAgreement, TheSimulatorsLagIsWhatTheAgreementEstimates) {
  const SimulatedPair p = simulated_pair(2.0);
  ASSERT_TRUE(p.tc_fit.ok() && p.air_fit.ok()) << p.tc_fit.brief_report() << p.air_fit.brief_report();
  const auto estimate = fitting::estimate_lag(p.tc, p.tc_fit, p.air);
  ASSERT_TRUE(estimate);
  EXPECT_NEAR(estimate->time_constant_s, 2.0, std::max(0.3, 3.0 * estimate->std_error_s));
  const auto agreement = fitting::compare_fits(p.tc_fit, p.air_fit, p.tc, p.air);
  EXPECT_EQ(agreement.lag.source, "estimated") << agreement.brief_report();
}

TEST(ProcessAgreement, TheDemosStatedLagIsRemovedNotReportedAsDisagreement) {
  const SimulatedPair p = simulated_pair(0.5);  // the demo's thermocouples (sim/demo_setup.h)
  fitting::AgreementOptions given;
  given.a_time_constant_s = 0.5;
  const auto result = fitting::compare_fits(p.tc_fit, p.air_fit, p.tc, p.air, given);
  ASSERT_TRUE(result.curve && result.series) << result.brief_report();
  EXPECT_EQ(result.curve->verdict, fitting::Verdict::kAgree) << result.brief_report();
  EXPECT_LT(std::abs(result.series->bias_c), 0.5 * std::abs(result.series->bias_as_read_c)) << result.brief_report();
  EXPECT_GT(result.series->bias_as_read_c, 0.0) << "as read, the lagging sensor is warmer while cooling";
}

}  // namespace
}  // namespace bosfuse::pipeline
