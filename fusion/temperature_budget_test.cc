#include "fusion/temperature_budget.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace bosfuse::fusion {
namespace {

BosGeometryOptions set_up() {
  BosGeometryOptions o;
  o.ambient_temperature_c = 21;
  o.ambient_pressure_pa = 100'500;
  o.z_d_m = 0.45;
  o.depth_m = 0.12;
  o.magnification = 0.2;
  o.pixel_pitch_um = 4.8;
  return o;
}

// The index change a measurement of `temperature_c` integrates to, in the
// units the solve gives it: proportional to 1 / (Z_D · L · M^m), fixed by the shifts.
double integrated_dn(const BosGeometry& g, double temperature_c) {
  return g.refractive_index(temperature_c) - g.ambient_refractive_index();
}

// T after one input changed, the shifts (so δn · gradient scale) kept: what
// the budget's sensitivities must be the derivatives of.
double temperature_after(const BosGeometry& measured, const BosGeometryOptions& changed, double temperature_c) {
  const BosGeometry g(changed);
  const double scale = (g.gradient_per_m(1.0) / measured.gradient_per_m(1.0)) *
                       (measured.px_per_m_flow() / g.px_per_m_flow());
  return g.temperature_c(g.ambient_refractive_index() + integrated_dn(measured, temperature_c) * scale);
}

const BudgetComponent& named(const TemperatureBudget& b, const std::string& prefix) {
  for (const auto& c : b.components) {
    if (c.quantity.rfind(prefix, 0) == 0) return c;
  }
  throw std::runtime_error("no component " + prefix);
}

TEST(TemperatureBudget, SensitivitiesAreTheDerivativesOfTheBosGeometryChain) {
  for (const bool derived_scale : {true, false}) {
    BosGeometryOptions o = set_up();
    if (!derived_scale) o.px_per_mm_flow = 41.7;
    const BosGeometry g(o);
    for (const double t_c : {22.0, 45.0, 80.0, 5.0}) {
      SCOPED_TRACE(testing::Message() << "T = " << t_c << " derived scale " << derived_scale);
      const auto budget = temperature_budget(g, {}, t_c);
      const double h = 1e-5;
      auto relative = [&](auto change) {
        BosGeometryOptions c = o;
        change(c);
        return (temperature_after(g, c, t_c) - t_c) / h;
      };
      BosGeometryOptions warmer = o;
      warmer.ambient_temperature_c += 1e-3;
      EXPECT_NEAR(named(budget, "ambient temperature").sensitivity, (temperature_after(g, warmer, t_c) - t_c) / 1e-3,
                  1e-3);
      // Within 0.1 %: the chain's 1/n0 in the deflection, which the budget
      // leaves out, is 3e-4 of a pressure's effect.
      auto near = [](double analytic, double numeric) { EXPECT_NEAR(analytic, numeric, 1e-3 * std::abs(numeric)); };
      near(named(budget, "ambient pressure").sensitivity,
           relative([&](auto& c) { c.ambient_pressure_pa *= 1 + h; }) / o.ambient_pressure_pa);
      near(named(budget, "Z_D").sensitivity, relative([&](auto& c) { c.z_d_m *= 1 + h; }));
      near(named(budget, "depth").sensitivity, relative([&](auto& c) { c.depth_m *= 1 + h; }));
      near(named(budget, "magnification").sensitivity, relative([&](auto& c) { c.magnification *= 1 + h; }));
      // K by its wavelength: the relative change of K that a changed λ makes.
      BosGeometryOptions bluer = o;
      bluer.wavelength_nm = 450;
      const double k_relative = BosGeometry(bluer).gladstone_dale_m3_per_kg() / g.gladstone_dale_m3_per_kg() - 1;
      EXPECT_NEAR(named(budget, "Gladstone").sensitivity * k_relative, temperature_after(g, bluer, t_c) - t_c,
                  0.02 * std::abs(temperature_after(g, bluer, t_c) - t_c) + 1e-9);
    }
  }
}

TEST(TemperatureBudget, CombinesItsPartsAsTheRootSumOfSquares) {
  const BosGeometry g(set_up());
  TypeBUncertainties u;
  u.depth_relative = 0.05;
  const auto budget = temperature_budget(g, u, 61.0, 0.3);
  double sum_sq = 0;
  for (const auto& c : budget.components) {
    EXPECT_DOUBLE_EQ(c.contribution_c, std::abs(c.sensitivity) * c.standard_uncertainty) << c.quantity;
    sum_sq += c.contribution_c * c.contribution_c;
  }
  EXPECT_DOUBLE_EQ(budget.combined_c, std::sqrt(sum_sq));
  EXPECT_DOUBLE_EQ(named(budget, "window").contribution_c, 0.3);
  // The excess of 40 °C scaled by about 5 % (the depth) is the largest part.
  EXPECT_NEAR(named(budget, "depth").contribution_c, 0.05 * (61.0 - 21.0) * (334.15 / 294.15), 0.05);
  const std::string table = budget.table();
  EXPECT_NE(table.find("| depth L (line of sight) | 0.05 relative |"), std::string::npos) << table;
  EXPECT_NE(table.find("combined"), std::string::npos) << table;
}

TEST(TemperatureBudget, AtAmbientOnlyTheAmbientTemperatureCounts) {
  const BosGeometry g(set_up());
  const auto budget = temperature_budget(g, {}, 21.0);
  EXPECT_NEAR(budget.combined_c, TypeBUncertainties{}.ambient_temperature_c, 1e-9);
}

TEST(TemperatureBudget, RefusesUncertaintiesThatAreNotNumbersOrNegative) {
  const BosGeometry g(set_up());
  TypeBUncertainties u;
  u.z_d_relative = -0.01;
  EXPECT_THROW(temperature_budget(g, u, 30.0), std::invalid_argument);
  u = {};
  u.ambient_pressure_pa = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(u.Validate().find("ambient_pressure_pa"), std::string::npos);
  EXPECT_THROW(temperature_budget(g, {}, -300.0), std::invalid_argument);
}

TemperatureField paraboloid(double curvature_c_per_px2) {
  TemperatureField f;
  f.rows = 7;
  f.cols = 9;
  f.x0_px = 8;
  f.y0_px = 8;
  f.step_px = 8;
  for (int r = 0; r < f.rows; ++r) {
    for (int c = 0; c < f.cols; ++c) {
      const double x = f.x0_px + c * f.step_px - 40, y = f.y0_px + r * f.step_px - 30;
      f.temperature_c.push_back(30 + curvature_c_per_px2 * (x * x + y * y));
      f.measured.push_back(1);
      f.physical.push_back(1);
      f.refractive_index.push_back(1.0002);
    }
  }
  return f;
}

TEST(WindowAverage, IsTheWindowsMeanAgainstItsCentreForACurvedField) {
  const TemperatureField f = paraboloid(-0.002);
  // ∇²T = 4 · (−0.002) °C/px², for a 16 px window: 16² / 24 · 0.008.
  const auto u = window_average_uncertainty_c(f, 41, 31, 16);
  ASSERT_TRUE(u);
  EXPECT_NEAR(*u, 16.0 * 16.0 / 24.0 * 0.008, 1e-9);
  // The mean of the paraboloid over the window's 16 × 16 pixels, against
  // its centre, directly: (w² − 1) / 24 for pixels rather than w² / 24.
  double mean = 0;
  for (int i = -8; i < 8; ++i) {
    for (int j = -8; j < 8; ++j) mean += -0.002 * ((i + 0.5) * (i + 0.5) + (j + 0.5) * (j + 0.5));
  }
  EXPECT_NEAR(std::abs(mean / 256), *u, *u / 256 + 1e-12);
}

TEST(WindowAverage, IsUnknownNextToAnUnmeasuredNodeOrOffTheGrid) {
  TemperatureField f = paraboloid(0.001);
  EXPECT_FALSE(window_average_uncertainty_c(f, 8, 8, 16)) << "a corner node has no four neighbours";
  EXPECT_FALSE(window_average_uncertainty_c(f, 500, 30, 16));
  f.measured[f.index(3, 5)] = 0;
  EXPECT_FALSE(window_average_uncertainty_c(f, 40, 32, 16)) << "its right neighbour was filled, not measured";
  EXPECT_TRUE(window_average_uncertainty_c(f, 16, 16, 16));
}

}  // namespace
}  // namespace bosfuse::fusion
