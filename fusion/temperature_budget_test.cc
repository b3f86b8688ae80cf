#include "fusion/temperature_budget.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>

#include <Eigen/Dense>

#include "fusion/displacement_evaluator.h"
#include "sim/synthetic_pair.h"

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

TEST(WindowCorrection, AtANodeIsMinusTheChainsCoefficientTimesTheLaplacian) {
  const TemperatureField f = paraboloid(-0.002);  // ∇²T = 4 · (−0.002) °C/px²
  const CurvatureCoefficient box{16.0 * 16.0 / 24.0, 1.0};
  const auto c = window_correction(f, 40, 32, box);  // a node: no interpolation term
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->laplacian_c_per_px2, -0.008, 1e-12);
  EXPECT_NEAR(c->correction_c, 16.0 * 16.0 / 24.0 * 0.008, 1e-9) << "a concave field reads low: added back";
  EXPECT_NEAR(c->coefficient_sigma_c, 0.008, 1e-12);
  double combined = 0;
  for (std::size_t k = 0; k < c->nodes.size(); ++k) combined += c->weights[k] * f.temperature_c[c->nodes[k]];
  EXPECT_NEAR(combined, c->correction_c, 1e-12) << "the weights are the correction, for its noise's propagation";
  // The box's mean over its 16 × 16 pixels, against its centre, directly,
  // is what the correction undoes: (w² − 1) / 24 for pixels, not w² / 24.
  double mean = 0;
  for (int i = -8; i < 8; ++i) {
    for (int j = -8; j < 8; ++j) mean += -0.002 * ((i + 0.5) * (i + 0.5) + (j + 0.5) * (j + 0.5));
  }
  EXPECT_NEAR(-mean / 256, c->correction_c, c->correction_c / 256 + 1e-12);
}

TEST(WindowCorrection, BetweenNodesAddsTheBilinearInterpolationsExactTerm) {
  const TemperatureField f = paraboloid(-0.002);
  const CurvatureCoefficient none{0, 0};
  // Half-way between nodes along x (a = 0.5), on a node along y: the
  // interpolation of a parabola reads low by a(1 − a)·h²/2 · ∂²T/∂x².
  const double x = 44, y = 32;
  const auto c = window_correction(f, x, y, none);
  ASSERT_TRUE(c);
  const double truth = 30 - 0.002 * ((x - 40) * (x - 40) + (y - 30) * (y - 30));
  EXPECT_NEAR(*f.temperature_at(x, y) + c->correction_c, truth, 1e-9);
  EXPECT_GT(c->correction_c, 0.0);
}

TEST(WindowCorrection, ItsSigmaIsTheCoefficientsAndTheNoiseCombinedOrTheWholeCorrectionWithoutNoise) {
  WindowCorrection c;
  c.correction_c = 0.3;
  c.coefficient_sigma_c = 0.04;
  EXPECT_NEAR(window_correction_sigma_c(c, 0.03), 0.05, 1e-12);
  EXPECT_NEAR(window_correction_sigma_c(c, std::nullopt), std::hypot(0.04, 0.3), 1e-12);
  EXPECT_NEAR(window_correction_sigma_c(c, std::numeric_limits<double>::quiet_NaN()), std::hypot(0.04, 0.3), 1e-12);
}

TEST(WindowCorrection, IsUnknownNextToAnUnmeasuredNodeOrOffTheGrid) {
  TemperatureField f = paraboloid(0.001);
  const CurvatureCoefficient box{10, 1};
  EXPECT_FALSE(window_correction(f, 8, 8, box)) << "a corner node has no four neighbours";
  EXPECT_FALSE(window_correction(f, 500, 30, box));
  f.measured[f.index(3, 5)] = 0;
  EXPECT_FALSE(window_correction(f, 40, 32, box)) << "its right neighbour was filled, not measured";
  EXPECT_TRUE(window_correction(f, 16, 16, box));
}

TEST(WindowCorrection, TheChainsCoefficientFollowsTheOptions) {
  EvaluatorOptions deformed;  // the defaults: 16 px, 3 deformed passes
  const auto d = chain_curvature_coefficient(deformed, 8);
  EXPECT_NEAR(d.kappa_px2, 4.0, 1e-12) << "the solve's h²/16 and a deformed window's 0";
  EXPECT_NEAR(d.effective_window_px(), std::sqrt(96.0), 1e-12);
  EvaluatorOptions box = deformed;
  box.xcorr.deform = false;
  EXPECT_NEAR(chain_curvature_coefficient(box, 8).kappa_px2, 16.0 * 16.0 / 24 + 4, 1e-12);
  EvaluatorOptions wide = deformed;
  wide.xcorr.window_px = 32;
  EXPECT_NEAR(chain_curvature_coefficient(wide, 16).sigma_px2, 4 * d.sigma_px2, 1e-12);
}

// κ of the whole chain measured on a generated plume: the refractive-index
// change the solve gives at each node regressed on the truth's φ and ∇²φ
// (and a constant), δn = s·(φ + κ·∇²φ) + c, so κ needs no sensitivity.
// The plume is sim's Gaussian bump (φ = h·exp(−r²/2r0²), its gradient the
// shift), within 3 r0 of its centre.
double measured_kappa_px2(const TemperatureField& f, const sim::DisplacementModel& bump) {
  const double r0 = bump.radius_px, height = std::abs(bump.amplitude_px) * r0 * std::exp(0.5);
  std::vector<double> rows;
  Eigen::MatrixXd a(f.temperature_c.size(), 3);
  Eigen::VectorXd b(f.temperature_c.size());
  int n = 0;
  for (int r = 0; r < f.rows; ++r) {
    for (int c = 0; c < f.cols; ++c) {
      const double x = f.x0_px + c * f.step_px - bump.centre_x_px, y = f.y0_px + r * f.step_px - bump.centre_y_px;
      const double r2 = x * x + y * y;
      if (r2 > 9 * r0 * r0) continue;
      const double phi = height * std::exp(-r2 / (2 * r0 * r0));
      a.row(n) << phi, phi * (r2 / (r0 * r0 * r0 * r0) - 2 / (r0 * r0)), 1.0;
      b(n++) = f.refractive_index[f.index(r, c)] - 1;
    }
  }
  const Eigen::VectorXd coef = a.topRows(n).colPivHouseholderQr().solve(b.head(n));
  return coef(1) / coef(0);
}

BosGeometryOptions camera_set_up() {
  BosGeometryOptions o;
  o.z_d_m = 0.5;
  o.depth_m = 0.1;
  o.magnification = 0.15;
  o.pixel_pitch_um = 5.0;
  return o;
}

// The chain's κ over six seeds' images of a plume of radius 32 px, peak
// shift 0.3 px, 1 % noise: the mean, as w_eff = sqrt(24 κ).
double measured_chain_width_px(const EvaluatorOptions& options) {
  std::vector<double> kappas;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    sim::PairOptions pair;
    pair.pattern.width_px = pair.pattern.height_px = 320;
    pair.pattern.seed = seed;
    pair.noise_seed = 100 + seed;
    pair.field = sim::DisplacementModel::bump_gradient(160, 160, 32, -0.3);
    const auto images = sim::render_pair(pair);
    const auto evaluated = evaluate_displacement(images.reference, images.measurement, options);
    const auto solved = recover_temperature_field(evaluated.field, BosGeometry(camera_set_up()));
    kappas.push_back(measured_kappa_px2(solved.field, pair.field));
  }
  const double kappa = std::accumulate(kappas.begin(), kappas.end(), 0.0) / kappas.size();
  return std::sqrt(24 * std::max(kappa, 0.0));
}

TEST(WindowCorrection, TheDefaultChainsWidthIsWhatAGeneratedPlumeMeasures) {
  EvaluatorOptions options;
  options.set_grid(16, 8);
  const double stated = chain_curvature_coefficient(options, 8).effective_window_px();
  const double measured = measured_chain_width_px(options);
  std::printf("default chain (16 px, 3 deformed passes, step 8): w_eff measured %.2f px, stated %.2f px\n", measured,
              stated);
  RecordProperty("measured_effective_window_px", std::to_string(measured));
  EXPECT_NEAR(measured, stated, 0.2 * stated);
}

TEST(WindowCorrection, AChainWithoutDeformationAveragesOverItsBoxAndTheSolve) {
  EvaluatorOptions options;
  options.set_grid(16, 8);
  options.xcorr.deform = false;
  const double stated = chain_curvature_coefficient(options, 8).effective_window_px();
  const double measured = measured_chain_width_px(options);
  std::printf("16 px without deformation, step 8: w_eff measured %.2f px, stated %.2f px\n", measured, stated);
  EXPECT_NEAR(measured, stated, 0.2 * stated);
}

TEST(WindowCorrection, TheSolvesOwnSmoothingIsTheStepSquaredOverSixteen) {
  // Exact shifts at the nodes: what is left is the solve's h²/16.
  for (const int step : {4, 8}) {
    const auto bump = sim::DisplacementModel::bump_gradient(160, 160, 32, -0.3);
    DisplacementField exact;
    exact.rows = exact.cols = 320 / step;
    for (int r = 0; r < exact.rows; ++r) {
      for (int c = 0; c < exact.cols; ++c) {
        DisplacementVector v;
        v.x_px = step / 2.0 + c * step;
        v.y_px = step / 2.0 + r * step;
        const auto shift = bump.at(v.x_px, v.y_px);
        v.u_px = shift.x;
        v.v_px = shift.y;
        exact.vectors.push_back(v);
      }
    }
    const auto solved = recover_temperature_field(exact, BosGeometry(camera_set_up()));
    EXPECT_NEAR(measured_kappa_px2(solved.field, bump), step * step / 16.0, 0.05 * step * step / 16.0) << step;
  }
}

}  // namespace
}  // namespace bosfuse::fusion
