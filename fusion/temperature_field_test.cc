// Physics of shift → temperature: a known temperature field, its analytic
// refractive-index gradient and displacement, and the recovered field.

#include "fusion/temperature_field.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

// A Gaussian hot spot: T = T0 + A·exp(−r²/2s²), all lengths in px.
struct HotSpot {
  double x_px, y_px, sigma_px, rise_c;
  double temperature_c(const BosGeometry& g, double x, double y) const {
    const double r2 = (x - x_px) * (x - x_px) + (y - y_px) * (y - y_px);
    return g.options().ambient_temperature_c + rise_c * std::exp(-r2 / (2 * sigma_px * sigma_px));
  }
};

// Displacement at the grid nodes from the analytic gradient
// ∂n/∂x = dn/dT · ∂T/∂x, dn/dT = −K p / (R T²).
DisplacementField analytic_displacement(const HotSpot& spot, const BosGeometry& g, int rows, int cols, double step_px) {
  DisplacementField field;
  field.rows = rows;
  field.cols = cols;
  const double px_per_m = g.px_per_m_flow();
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      DisplacementVector v;
      v.x_px = 7.5 + c * step_px;
      v.y_px = 7.5 + r * step_px;
      const double t_k = spot.temperature_c(g, v.x_px, v.y_px) + kZeroCelsiusK;
      const double rise = t_k - g.ambient_temperature_k();
      const double dt_dx_per_px = -rise * (v.x_px - spot.x_px) / (spot.sigma_px * spot.sigma_px);
      const double dt_dy_per_px = -rise * (v.y_px - spot.y_px) / (spot.sigma_px * spot.sigma_px);
      const double dn_dt =
          -g.gladstone_dale_m3_per_kg() * g.options().ambient_pressure_pa / (kSpecificGasConstantAir * t_k * t_k);
      v.u_px = g.shift_px(dn_dt * dt_dx_per_px * px_per_m);
      v.v_px = g.shift_px(dn_dt * dt_dy_per_px * px_per_m);
      field.vectors.push_back(v);
    }
  }
  return field;
}

BosGeometryOptions paper_like_setup() {
  BosGeometryOptions o;
  o.z_d_m = 0.5;
  o.depth_m = 0.1;
  o.magnification = 0.15;
  o.pixel_pitch_um = 5.0;  // 30 px/mm at the background, as in the paper
  return o;
}

TEST(BosGeometry, GladstoneDaleAndAmbientAir) {
  const BosGeometry g(paper_like_setup());
  // 2.2244e-4·(1 + (6.7132e-8/550e-9)²) = 2.2575e-4 m³/kg.
  EXPECT_NEAR(g.gladstone_dale_m3_per_kg(), 2.2575e-4, 1e-7);
  EXPECT_NEAR(g.ambient_density_kg_per_m3(), 1.2041, 1e-3);  // 101325 / (287.05 · 293.15)
  EXPECT_NEAR(g.ambient_refractive_index() - 1, 2.718e-4, 1e-6);
  EXPECT_NEAR(g.temperature_c(g.refractive_index(63.0)), 63.0, 1e-9);
  EXPECT_TRUE(std::isnan(g.temperature_c(0.9999))) << "n below 1 is no gas";
  EXPECT_NEAR(g.px_per_m_flow(), 30e3, 1e-6);
  EXPECT_NEAR(g.gradient_per_m(g.shift_px(3e-5)), 3e-5, 1e-15);
}

TEST(BosGeometry, InvalidSetupsAreNamed) {
  auto o = paper_like_setup();
  o.z_d_m = 0;
  EXPECT_NE(o.Validate().find("z_d_m"), std::string::npos);
  EXPECT_THROW(BosGeometry{o}, std::invalid_argument);
  o = paper_like_setup();
  o.wavelength_nm = std::nan("");
  EXPECT_NE(o.Validate().find("wavelength"), std::string::npos);
}

TEST(BosGeometry, SensitivityScalesWithTheGeometry) {
  const BosGeometry base(paper_like_setup());
  auto farther = paper_like_setup();
  farther.z_d_m *= 2;  // twice the lever arm: half the temperature per px
  EXPECT_NEAR(BosGeometry(farther).celsius_per_px_shift_per_px_length(), base.celsius_per_px_shift_per_px_length() / 2,
              1e-12);
  // Hand calculation: |dn/dx| for 1 px = p·n0/(M·Z_D·L) = 5e-6·1.000272/(0.15·0.5·0.1) = 6.669e-4 1/m;
  // per px of length ÷ 30e3 px/m, × T0/(n0 − 1) = 293.15/2.718e-4.
  EXPECT_NEAR(base.celsius_per_px_shift_per_px_length(), 6.669e-4 / 30e3 * 293.15 / 2.718e-4, 2e-4);
  EXPECT_NE(base.brief_report().find("degC per px"), std::string::npos);
}

TEST(BosGeometry, HotSpotPullsTheBackgroundInwards) {
  // Lower n at a hot centre: right of it ∂n/∂x > 0, and the feature moves left (towards the centre).
  const BosGeometry g(paper_like_setup());
  const HotSpot spot{60, 60, 40, 30};
  const auto field = analytic_displacement(spot, g, 3, 3, 40);  // node (1, 1) at (47.5, 47.5): up left of the centre
  EXPECT_GT(field.at(1, 1).u_px, 0) << "left of a hot spot the shift points right, towards it";
  EXPECT_GT(field.at(1, 1).v_px, 0);
}

// The acceptance test: Gaussian hot spot, 30 °C rise, 64×48 nodes at 16 px
// (a 1024×768 image), σ = 80 px (5 nodes). Measured: peak rise 29.67 °C for
// 29.78 °C (−0.37%), RMS error 0.018 °C, largest error 0.15 °C.
TEST(TemperatureField, RecoversAGaussianHotSpotFromItsAnalyticDisplacement) {
  const BosGeometry g(paper_like_setup());
  const HotSpot spot{512, 380, 80, 30};
  const auto displacement = analytic_displacement(spot, g, 48, 64, 16);
  const auto result = recover_temperature_field(displacement, g);
  const auto& field = result.field;
  double peak = -1e9, sum_sq = 0, max_error = 0;
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const double x = field.x0_px + c * field.step_px, y = field.y0_px + r * field.step_px;
      const double t = field.temperature_c[field.index(r, c)];
      const double error = t - spot.temperature_c(g, x, y);
      sum_sq += error * error;
      max_error = std::max(max_error, std::abs(error));
      peak = std::max(peak, t);
    }
  }
  const double true_peak = spot.temperature_c(g, 503.5, 375.5) - 20;  // the node nearest the centre
  const double rms = std::sqrt(sum_sq / static_cast<double>(field.temperature_c.size()));
  EXPECT_NEAR(peak - 20, true_peak, 0.02 * true_peak) << "peak rise within 2%";
  EXPECT_LT(rms, 0.1) << "RMS error below 0.1 degC";
  EXPECT_LT(max_error, 0.5);
  EXPECT_EQ(result.summary.unmeasured_nodes, 0u);
  EXPECT_EQ(result.summary.boundary_nodes, 2u * 64 + 2u * 46);
  RecordProperty("rms_error_c", std::to_string(rms));
  RecordProperty("peak_error_fraction", std::to_string((peak - 20 - true_peak) / true_peak));
  std::printf("hot spot: true peak rise %.4f, recovered %.4f degC; RMS error %.5f, max %.5f degC\n", true_peak,
              peak - 20, rms, max_error);
}

TEST(TemperatureField, MaskedNodesAreFilledFromTheirSurroundings) {
  const BosGeometry g(paper_like_setup());
  const HotSpot spot{512, 380, 80, 30};
  auto displacement = analytic_displacement(spot, g, 48, 64, 16);
  for (int r = 30; r < 36; ++r) {  // a holder below the hot spot, 6×6 nodes
    for (int c = 28; c < 34; ++c) {
      displacement.at(r, c).flag = VectorFlag::kMasked;
      displacement.at(r, c).u_px = 50;  // must not enter: masked values are not measurements
    }
  }
  const auto result = recover_temperature_field(displacement, g);
  EXPECT_EQ(result.summary.unmeasured_nodes, 36u);
  const auto at_peak = result.field.temperature_at(spot.x_px, spot.y_px);
  ASSERT_TRUE(at_peak.has_value());
  EXPECT_NEAR(*at_peak - 20, 30, 0.03 * 30);
  for (int r = 30; r < 36; ++r) {
    for (int c = 28; c < 34; ++c) EXPECT_TRUE(std::isfinite(result.field.temperature_c[result.field.index(r, c)]));
  }
  EXPECT_FALSE(result.field.measured[result.field.index(31, 29)]);
}

TEST(TemperatureField, UniformFieldIsAmbientAndProbeFieldsAreRefused) {
  const BosGeometry g(paper_like_setup());
  const HotSpot none{0, 0, 10, 0};
  const auto result = recover_temperature_field(analytic_displacement(none, g, 5, 6, 8), g);
  for (double t : result.field.temperature_c) EXPECT_NEAR(t, 20, 1e-9);
  DisplacementField probes;
  probes.rows = 1;
  probes.cols = 2;
  probes.vectors.resize(2);
  EXPECT_THROW(recover_temperature_field(probes, g), std::invalid_argument);
}

// End to end through DESIGN.md's displacement convention: a synthetic pair
// whose background features move towards a centre (what a hot spot does,
// per bos_geometry.h) is evaluated and integrated — the result must be hot.
TEST(TemperatureField, InwardDisplacementFromImagesIsAHotSpot) {
  sim::PairOptions pair;
  pair.pattern.width_px = 256;
  pair.pattern.height_px = 256;
  pair.field = sim::DisplacementModel::bump_gradient(128, 128, 30, -0.5);  // negative: pointing inwards
  const auto images = sim::render_pair(pair);
  EvaluatorOptions options;
  options.set_grid(16, 8);
  const auto evaluated = evaluate_displacement(images.reference, images.measurement, options);
  const BosGeometry g(paper_like_setup());
  const auto result = recover_temperature_field(evaluated.field, g);
  const auto centre = result.field.temperature_at(128, 128);
  ASSERT_TRUE(centre.has_value());
  // The sim's field is the gradient of φ = h·exp(−r²/2s²), h = 0.5·30·√e px²;
  // linearised, the centre's rise is h times the set-up's sensitivity.
  const double expected_rise = 0.5 * 30 * std::exp(0.5) * g.celsius_per_px_shift_per_px_length();
  EXPECT_GT(*centre - 20, 0) << "inward shifts must integrate to a hot spot";
  EXPECT_NEAR(*centre - 20, expected_rise, 0.15 * expected_rise);
}

TEST(TemperatureField, TheCsvHasANodePerLineAndAnEmptyCellWhereNoTemperatureExists) {
  TemperatureField field;
  field.rows = 1;
  field.cols = 2;
  field.x0_px = 7.5;
  field.y0_px = 7.5;
  field.step_px = 8;
  field.temperature_c = {25.5, std::nan("")};
  field.measured = {1, 0};
  const auto path = std::filesystem::temp_directory_path() / "bosfuse-temperature-csv-test.csv";
  write_csv(field, path);
  std::ifstream in(path);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::filesystem::remove(path);
  EXPECT_EQ(text, "x,y,temperature_c,measured\n7.5,7.5,25.5000,1\n15.5,7.5,,0\n");
}

}  // namespace
}  // namespace bosfuse::fusion

namespace bosfuse::fusion {
namespace {

// Heated air leaving through the top of the image (a plume rising out of
// view): held at ambient there the field comes out too cold; declared open,
// the top edge follows the measured gradients.
TEST(TemperatureField, OpenEdgeLetsTheHeatedRegionLeaveTheImage) {
  const BosGeometry g(paper_like_setup());
  const HotSpot spot{160, -10, 40, 20};  // centred just above the image
  const DisplacementField shifts = analytic_displacement(spot, g, 30, 40, 8);
  const auto worst_error = [&](const TemperatureFieldOptions& options) {
    const auto recovered = recover_temperature_field(shifts, g, options);
    double worst = 0;
    for (int r = 0; r < shifts.rows; ++r) {
      for (int c = 0; c < shifts.cols; ++c) {
        const auto& v = shifts.at(r, c);
        const double truth = spot.temperature_c(g, v.x_px, v.y_px);
        worst = std::max(worst, std::abs(recovered.field.temperature_c[recovered.field.index(r, c)] - truth));
      }
    }
    return worst;
  };
  TemperatureFieldOptions open;
  open.open_top = true;
  const double closed_error = worst_error({}), open_error = worst_error(open);
  EXPECT_GT(closed_error, 10.0);  // the top row forced to ambient, though it is ~19 °C warmer
  EXPECT_LT(open_error, 0.5);
  TemperatureFieldOptions all_open = open;
  all_open.open_bottom = all_open.open_left = all_open.open_right = true;
  EXPECT_NE(all_open.Validate().find("ambient"), std::string::npos);
}

}  // namespace
}  // namespace bosfuse::fusion

namespace bosfuse::fusion {
namespace {

// Largest difference of δn = n − n0 between two fields, relative to the
// largest |δn| of `fresh`.
double relative_difference(const TemperatureField& kept, const TemperatureField& fresh, const BosGeometry& g) {
  EXPECT_EQ(kept.refractive_index.size(), fresh.refractive_index.size());
  double largest = 0, difference = 0;
  for (std::size_t i = 0; i < fresh.refractive_index.size() && i < kept.refractive_index.size(); ++i) {
    largest = std::max(largest, std::abs(fresh.refractive_index[i] - g.ambient_refractive_index()));
    difference = std::max(difference, std::abs(kept.refractive_index[i] - fresh.refractive_index[i]));
  }
  return difference / largest;
}

DisplacementField with_masked_block(DisplacementField field, int row0, int col0, int size) {
  for (int r = row0; r < row0 + size; ++r) {
    for (int c = col0; c < col0 + size; ++c) field.at(r, c).flag = VectorFlag::kMasked;
  }
  return field;
}

// A run's frames through one solver: the second frame keeps the first one's
// unmeasured nodes (factor reused, only solved), the third masks others
// (refactorised on the kept analysis). Each must equal a fresh one-shot
// solve. The one-shot form orders the matrix by AMD, the kept solver by
// nested dissection, so the two round differently (~1e-16 of δn); but the
// field holds n = n0 + δn, whose last bit is ~4e-12 of the largest δn here,
// so 1e-10 allows a few bits of n and nothing of the physics (the solve's
// own error is ~1e-3 of δn). Measured: n bit-equal on every frame.
TEST(TemperatureFieldSolver, FramesEqualFreshSolves) {
  const BosGeometry g(paper_like_setup());
  const std::vector<DisplacementField> frames = {
      with_masked_block(analytic_displacement(HotSpot{512, 380, 80, 30}, g, 48, 64, 16), 30, 28, 6),
      with_masked_block(analytic_displacement(HotSpot{420, 300, 60, 45}, g, 48, 64, 16), 30, 28, 6),
      with_masked_block(analytic_displacement(HotSpot{600, 200, 90, 20}, g, 48, 64, 16), 10, 40, 8),
  };
  for (const PoissonSolver kind : {PoissonSolver::kCholmodSupernodal, PoissonSolver::kEigenSimplicial}) {
    TemperatureFieldOptions options;
    options.solver = kind;
    options.open_top = true;  // the open edge's unknowns too
    TemperatureFieldSolver solver(g, options);
    double previous_peak = 0;
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const auto kept = solver.recover(frames[f]);
      const auto fresh = recover_temperature_field(frames[f], g, options);
      const double difference = relative_difference(kept.field, fresh.field, g);
      EXPECT_LT(difference, 1e-10) << "frame " << f;
      std::printf("solver %d frame %zu: largest difference %.3g of the largest dn\n", static_cast<int>(kind), f,
                  difference);
      EXPECT_EQ(kept.field.measured, fresh.field.measured);
      EXPECT_EQ(kept.summary.unmeasured_nodes, fresh.summary.unmeasured_nodes);
      EXPECT_NEAR(kept.summary.max_c, fresh.summary.max_c, 1e-9);
      EXPECT_NE(kept.summary.max_c, previous_peak) << "each frame is its own field, not the one before";
      previous_peak = kept.summary.max_c;
    }
    EXPECT_EQ(solver.fields(), 3);
    EXPECT_EQ(solver.analyses(), 1);
    EXPECT_EQ(solver.factorisations(), 2) << "the second frame's unmeasured nodes are the first's";
  }
}

// The analysis done ahead of the first frame (as a run does it beside its
// first frames' evaluation) serves the frames: no second analysis, and
// fields equal to those of a solver that analysed at its first frame.
TEST(TemperatureFieldSolver, AnAnalysisAheadOfTheFramesServesThem) {
  const BosGeometry g(paper_like_setup());
  const std::vector<DisplacementField> frames = {
      with_masked_block(analytic_displacement(HotSpot{512, 380, 80, 30}, g, 48, 64, 16), 30, 28, 6),
      with_masked_block(analytic_displacement(HotSpot{600, 200, 90, 20}, g, 48, 64, 16), 10, 40, 8),
  };
  TemperatureFieldSolver prepared(g), at_first_frame(g);
  prepared.prepare(GridGeometry{7.5, 7.5, 16, 48, 64});
  EXPECT_EQ(prepared.analyses(), 1);
  EXPECT_EQ(prepared.factorisations(), 0);
  for (const auto& frame : frames) {
    const auto ahead = prepared.recover(frame), later = at_first_frame.recover(frame);
    EXPECT_EQ(ahead.field.temperature_c, later.field.temperature_c);
    EXPECT_EQ(ahead.field.measured, later.field.measured);
  }
  EXPECT_EQ(prepared.analyses(), 1);
  EXPECT_EQ(prepared.factorisations(), 2);
  EXPECT_THROW(prepared.prepare(GridGeometry{7.5, 7.5, 16, 2, 64}), std::invalid_argument);
}

// The two factorisations solve the same system.
TEST(TemperatureFieldSolver, CholmodAndEigenAgree) {
  const BosGeometry g(paper_like_setup());
  const auto frame = with_masked_block(analytic_displacement(HotSpot{512, 380, 80, 30}, g, 48, 64, 16), 30, 28, 6);
  TemperatureFieldOptions cholmod, eigen;
  cholmod.solver = PoissonSolver::kCholmodSupernodal;
  eigen.solver = PoissonSolver::kEigenSimplicial;
  const auto a = recover_temperature_field(frame, g, cholmod), b = recover_temperature_field(frame, g, eigen);
  EXPECT_LT(relative_difference(a.field, b.field, g), 1e-9);
}

// Another grid mid-run (a resumed run with other settings, a probe band) is
// analysed anew, and a return to the first grid too.
TEST(TemperatureFieldSolver, ANewGridIsAnalysedAnew) {
  const BosGeometry g(paper_like_setup());
  const HotSpot spot{300, 200, 60, 25};
  const auto large = analytic_displacement(spot, g, 40, 50, 12), small = analytic_displacement(spot, g, 30, 40, 16);
  TemperatureFieldSolver solver(g);
  for (const auto* frame : {&large, &small, &large}) {
    const auto kept = solver.recover(*frame);
    EXPECT_EQ(kept.field.rows, frame->rows);
    EXPECT_LT(relative_difference(kept.field, recover_temperature_field(*frame, g).field, g), 1e-10);
  }
  EXPECT_EQ(solver.analyses(), 3);
  DisplacementField probes;
  probes.rows = 1;
  probes.cols = 2;
  probes.vectors.resize(2);
  EXPECT_THROW(solver.recover(probes), std::invalid_argument);
  TemperatureFieldOptions invalid;
  invalid.fill_weight = 0;
  EXPECT_THROW(TemperatureFieldSolver(g, invalid), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fusion
