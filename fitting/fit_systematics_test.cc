// The budget propagated through a fit: a shift common to every sample moves
// T0 and T_amb by itself and leaves k; a scale of the excess moves T0 by the
// scaled excess and leaves k and T_amb; independent inputs add in squares.

#include "fitting/fit_systematics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/support/cooling_curve.h"

namespace bosfuse::fitting {
namespace {

struct Fitted {
  testing::CoolingRecord record;
  std::vector<double> sigma_c;
  NewtonFitOptions options;
  NewtonFit fit;
};

Fitted fitted_record(const testing::CoolingCurve& curve) {
  Fitted f;
  f.record = testing::sample_cooling(curve, 60, 10.0, 0.05, 17);
  f.sigma_c.assign(f.record.time_s.size(), 0.05);
  f.options.origin_s = 0.0;
  f.fit = fit_newton(f.record.time_s, f.record.temperature_c, f.sigma_c, f.options);
  return f;
}

TEST(FitSystematics, AnAmbientShiftMovesT0AndTAmbAndAScaleMovesOnlyT0) {
  const testing::CoolingCurve curve{22.0, 80.0, 0.006};
  const Fitted f = fitted_record(curve);
  ASSERT_TRUE(f.fit.ok());
  SystematicInput ambient{"ambient temperature", std::vector<double>(f.record.time_s.size(), 0.5)};
  SystematicInput depth{"depth L", {}};
  for (double t : f.record.time_s) depth.shift_c.push_back(0.05 * (curve.at(t) - curve.ambient_c));
  const FitSystematics s = propagate_systematics(f.record.time_s, f.record.temperature_c, f.sigma_c, f.options, f.fit,
                                                 {ambient, depth});
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(s.effects.size(), 2u);
  const ParameterShifts& a = s.effects[0].shift;
  EXPECT_NEAR(a.t0_c, 0.5, 1e-4);
  EXPECT_NEAR(a.t_amb_c, 0.5, 1e-4);
  EXPECT_NEAR(a.k_per_s, 0.0, 1e-6 * curve.k_per_s);
  const ParameterShifts& d = s.effects[1].shift;
  EXPECT_NEAR(d.t0_c, 0.05 * (f.fit.t0_c.value - f.fit.ambient_c.value), 0.01);
  EXPECT_NEAR(d.t_amb_c, 0.0, 0.01);
  EXPECT_NEAR(d.k_per_s, 0.0, 1e-3 * curve.k_per_s) << "a scale of the excess leaves the rate";
  EXPECT_NEAR(s.combined.t0_c, std::hypot(a.t0_c, d.t0_c), 1e-12);
  EXPECT_NEAR(s.combined.t_amb_c, std::hypot(a.t_amb_c, d.t_amb_c), 1e-12);
  EXPECT_GE(s.combined.k_per_s, 0.0);
}

TEST(FitSystematics, AFailedFitOrAMisfitInputGivesNone) {
  const Fitted f = fitted_record({22.0, 80.0, 0.006});
  const SystematicInput short_input{"Z_D", {0.1, 0.2}};
  const auto misfit =
      propagate_systematics(f.record.time_s, f.record.temperature_c, f.sigma_c, f.options, f.fit, {short_input});
  EXPECT_FALSE(misfit.ok);
  EXPECT_NE(misfit.message.find("Z_D"), std::string::npos);
  NewtonFit failed = f.fit;
  failed.summary.status = FitStatus::kTooFewPoints;
  EXPECT_FALSE(propagate_systematics(f.record.time_s, f.record.temperature_c, {}, f.options, failed, {}).ok);
  const auto none = propagate_systematics(f.record.time_s, f.record.temperature_c, f.sigma_c, f.options, f.fit, {});
  EXPECT_TRUE(none.ok);
  EXPECT_EQ(none.combined.t0_c, 0.0) << "no input, no systematic part";
}

}  // namespace
}  // namespace bosfuse::fitting
