// Where the demo's BOS k bias (issue 29: +0.6 % / +0.4 % over 20 seeds) is
// made, stage by stage, with the scene's truth at hand: the demo's analytic
// displacement (no images) through the pipeline's solve, and the demo's
// rendered frames through the evaluator and the solve. Each probe reads the
// solved field bilinearly; the reading is corrected with the exact
// interpolation term and the chain's κ = 4 px² times the true ∇²T (what
// process's window correction estimates), and k is fitted with a free ambient.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "fusion/displacement_evaluator.h"
#include "fusion/temperature_field.h"
#include "sim/demo_setup.h"
#include "sim/demo_truth.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::sim {
namespace {

constexpr double kChainKappaPx2 = 4.0;  // fusion/temperature_budget.h: the default chain's

double newton_rate(const std::vector<double>& t, const std::vector<double>& y, double k0) {
  double best = 1e300, best_k = k0;
  for (int i = -8000; i <= 8000; ++i) {  // ±4 % in steps of 5e-6
    const double k = k0 * (1 + i * 5e-6), n = static_cast<double>(t.size());
    double se = 0, see = 0, sy = 0, sye = 0;
    for (std::size_t j = 0; j < t.size(); ++j) {
      const double e = std::exp(-k * t[j]);
      se += e, see += e * e, sy += y[j], sye += y[j] * e;
    }
    const double det = n * see - se * se, a = (sy * see - se * sye) / det, b = (n * sye - se * sy) / det;
    double r = 0;
    for (std::size_t j = 0; j < t.size(); ++j) r += std::pow(y[j] - a - b * std::exp(-k * t[j]), 2);
    if (r < best) best = r, best_k = k;
  }
  return best_k;
}

fusion::BosGeometry demo_geometry(const DemoSetup& setup) {
  const auto& s = setup.scene;
  fusion::BosGeometryOptions g;
  g.z_d_m = s.z_d_m, g.depth_m = s.depth_m, g.pixel_pitch_um = setup.pixel_pitch_um;
  g.magnification = s.px_per_mm * setup.pixel_pitch_um * 1e-3, g.wavelength_nm = setup.wavelength_nm;
  g.ambient_pressure_pa = s.pressure_pa, g.ambient_temperature_c = s.ambient_c;
  return fusion::BosGeometry(g);
}

void mask_holder(const ConvectionScene& scene, fusion::DisplacementField& f) {
  const cv::Mat mask = scene.holder_mask();
  for (auto& v : f.vectors) {
    for (int dy = -8; dy < 8; ++dy)
      for (int dx = -8; dx < 8; ++dx) {
        const int x = static_cast<int>(v.x_px) + dx, y = static_cast<int>(v.y_px) + dy;
        if (x >= 0 && y >= 0 && x < mask.cols && y < mask.rows && mask.at<uchar>(y, x)) v.flag = fusion::VectorFlag::kMasked;
      }
  }
}

// The corrected probe temperature at height z: point + (BOS − bilinear truth of the nodes) − κ∇²T.
double corrected_probe_c(const ConvectionScene& scene, const fusion::TemperatureField& tf, double z_m, double t) {
  const cv::Point2d at = scene.image_position_px(0, z_m);
  const double fx = (at.x - tf.x0_px) / tf.step_px, fy = (at.y - tf.y0_px) / tf.step_px;
  const int c = static_cast<int>(fx), r = static_cast<int>(fy);
  const double a = fx - c, b = fy - r, h = tf.step_px, x0 = tf.x0_px + c * h, y0 = tf.y0_px + r * h;
  const auto truth = [&](double x, double y) {
    const auto p = scene.flow_position_m(x, y);
    return scene.temperature_c(p.x, p.y, t);
  };
  const auto node = [&](int dr, int dc) { return tf.temperature_c[(r + dr) * tf.cols + c + dc]; };
  const auto bilinear = [&](auto v00, auto v01, auto v10, auto v11) {
    return (1 - a) * (1 - b) * v00 + a * (1 - b) * v01 + (1 - a) * b * v10 + a * b * v11;
  };
  const double bos = bilinear(node(0, 0), node(0, 1), node(1, 0), node(1, 1));
  const double nodes = bilinear(truth(x0, y0), truth(x0 + h, y0), truth(x0, y0 + h), truth(x0 + h, y0 + h));
  const double laplacian = truth(at.x + 1, at.y) + truth(at.x - 1, at.y) + truth(at.x, at.y + 1) +
                           truth(at.x, at.y - 1) - 4 * truth(at.x, at.y);
  return scene.temperature_c(0, z_m, t) + (bos - nodes) - kChainKappaPx2 * laplacian;
}

// k of each probe (relative to the truth) from the analytic displacement on the demo's grid.
std::pair<double, double> analytic_chain_bias(double onset_m) {
  DemoSetup setup = demo_setup(240);
  setup.scene.plume_onset_m = onset_m;
  setup.model = std::make_shared<const ConvectionScene>(setup.scene);
  const ConvectionScene& scene = *setup.model;
  fusion::TemperatureFieldOptions o;
  o.open_top = true;
  std::vector<double> ts, y35, y45;
  for (double t = 10; t <= 230; t += 10) {
    fusion::DisplacementField f;
    f.rows = 54, f.cols = 59;  // the demo's 16 px windows at 8 px steps over 480 × 440
    for (int r = 0; r < f.rows; ++r)
      for (int c = 0; c < f.cols; ++c) {
        fusion::DisplacementVector v;
        v.x_px = 7.5 + 8 * c, v.y_px = 7.5 + 8 * r;
        const cv::Point2d d = scene.displacement_px(v.x_px, v.y_px, t);
        v.u_px = d.x, v.v_px = d.y;
        f.vectors.push_back(v);
      }
    mask_holder(scene, f);
    const auto tf = fusion::recover_temperature_field(f, demo_geometry(setup), o).field;
    ts.push_back(t), y35.push_back(corrected_probe_c(scene, tf, 0.035, t)), y45.push_back(corrected_probe_c(scene, tf, 0.045, t));
  }
  const double k = true_plume_cooling_rate(setup);
  return {newton_rate(ts, y35, k) / k - 1, newton_rate(ts, y45, k) / k - 1};
}

// The solve, its boundary (Dirichlet sides, open top), the Gladstone–Dale
// conversion and the window correction do not make the bias: noise-free and
// exact in the displacement, k comes out within 0.25 % of the point's, and
// below it, not above (measured −0.19 % / −0.16 % with the scene's step at
// the plume's foot, −0.09 % / −0.08 % with a 6 mm onset).
TEST(DemoChainBias, TheSolveAndTheCorrectionLeaveKWithinAQuarterPercent) {
  for (const double onset_m : {0.0, 0.006}) {
    const auto [k35, k45] = analytic_chain_bias(onset_m);
    fmt::print("onset {} mm: k {:+.3f} % (tc-35mm) {:+.3f} % (tc-45mm)\n", onset_m * 1e3, 100 * k35, 100 * k45);
    EXPECT_LT(std::abs(k35), 0.0025);
    EXPECT_LT(std::abs(k45), 0.0025);
  }
}

// BOSFUSE_CHAIN_BIAS_XCORR="key=value,…": the evaluator's options the
// diagnostic switches (passes, convergence, symmetric, smooth, interpolator
// 0 cubic / 1 Lanczos3 / 2 Lanczos4 / 3 B-spline 3 / 4 B-spline 5, subpixel and refinement_subpixel 0
// 3-point / 1 2-D fit, outliers, coarse, correlation 0 auto / 1 direct / 2 FFT).
fusion::EvaluatorOptions switched_options() {
  fusion::EvaluatorOptions e;
  const char* spec = std::getenv("BOSFUSE_CHAIN_BIAS_XCORR");
  if (!spec) return e;
  fusion::XcorrOptions& x = e.xcorr;
  std::stringstream items(spec);
  for (std::string item; std::getline(items, item, ',');) {
    const auto eq = item.find('=');
    const std::string key = item.substr(0, eq);
    const double value = std::atof(item.substr(eq + 1).c_str());
    if (key == "passes") x.passes = static_cast<int>(value);
    else if (key == "convergence") x.convergence_px = value;
    else if (key == "symmetric") x.symmetric_deformation = value != 0;
    else if (key == "smooth") x.smooth_predictor = value != 0;
    else if (key == "interpolator") x.interpolator = static_cast<fusion::Interpolator>(static_cast<int>(value));
    else if (key == "subpixel") x.subpixel = static_cast<fusion::SubpixelEstimator>(static_cast<int>(value));
    else if (key == "refinement_subpixel") x.refinement_subpixel = static_cast<fusion::SubpixelEstimator>(static_cast<int>(value));
    else if (key == "outliers") x.replace_outliers = value != 0;
    else if (key == "coarse") x.coarse_first_pass = value != 0;
    else if (key == "correlation") x.correlation = static_cast<fusion::CorrelationMethod>(static_cast<int>(value));
    else if (key == "first_window") x.first_window_px = static_cast<int>(value);
    else ADD_FAILURE() << "BOSFUSE_CHAIN_BIAS_XCORR: unknown key " << key;
  }
  return e;
}

// Diagnostic, not in the suite (about 30 s CPU): the rendered frames
// through the evaluator. Camera noise BOSFUSE_CHAIN_BIAS_NOISE (default 0),
// patterns 1..BOSFUSE_CHAIN_BIAS_SEEDS (default 4). With the demo's noise
// (0.01) over 16 patterns, k from the point's (tc-35mm / tc-45mm):
//   quintic B-spline deformation (the default)  +0.22 ± 0.14 / +0.16 ± 0.17 %
//   Lanczos-3 (interpolator=1, the former)      +0.73 ± 0.14 / +0.70 ± 0.17 %
//   Lanczos-4 (interpolator=2)                  −0.20 ± 0.15 / −0.21 ± 0.18 %
//   Lanczos-3, symmetric=1                      −1.45 ± 0.14 / −1.46 ± 0.17 %
//   Lanczos-3, passes=5 / smooth=0 / refinement_subpixel=1 / outliers=0:
//     +0.88 / +0.89 / +0.87 / +0.73 % (tc-35mm), all ± 0.15
// against −0.19 / −0.16 % from the analytic displacement (the test above):
// the deformation's interpolation made the bias (docs/UNCERTAINTY.md).
// Run: build/sim/sim_test --gtest_also_run_disabled_tests --gtest_filter='DemoChainBias.DISABLED_TheRendered*'
TEST(DemoChainBias, DISABLED_TheRenderedFramesThroughTheEvaluator) {
  DemoSetup setup = demo_setup(240);
  if (const char* onset = std::getenv("BOSFUSE_CHAIN_BIAS_ONSET")) {  // the plume's onset, m (default: the scene's step)
    setup.scene.plume_onset_m = std::atof(onset);
  }
  if (const char* scale = std::getenv("BOSFUSE_CHAIN_BIAS_ZD_SCALE")) setup.scene.z_d_m *= std::atof(scale);  // shifts × scale
  setup.model = std::make_shared<const ConvectionScene>(setup.scene);
  const ConvectionScene& scene = *setup.model;
  const double noise = std::getenv("BOSFUSE_CHAIN_BIAS_NOISE") ? std::atof(std::getenv("BOSFUSE_CHAIN_BIAS_NOISE")) : 0.0;
  const int seeds = std::getenv("BOSFUSE_CHAIN_BIAS_SEEDS") ? std::atoi(std::getenv("BOSFUSE_CHAIN_BIAS_SEEDS")) : 4;
  fusion::TemperatureFieldOptions o;
  o.open_top = true;
  o.weight_by_sigma = std::getenv("BOSFUSE_CHAIN_BIAS_UNWEIGHTED") == nullptr;
  const double k = true_plume_cooling_rate(setup);
  const fusion::EvaluatorOptions evaluator = switched_options();
  double sum35 = 0, sum45 = 0, sq35 = 0, sq45 = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    PatternOptions p;
    p.width_px = setup.scene.width_px, p.height_px = setup.scene.height_px, p.dot_diameter_px = 3;
    p.seed = static_cast<std::uint64_t>(seed);
    const BackgroundPattern pattern = generate_pattern(p);
    CameraModel camera;
    camera.noise_std = noise;
    CameraModel reference_camera = camera;  // BOSFUSE_CHAIN_BIAS_REFERENCE_NOISE: the reference's own noise
    if (const char* r = std::getenv("BOSFUSE_CHAIN_BIAS_REFERENCE_NOISE")) reference_camera.noise_std = std::atof(r);
    const cv::Mat reference = scene.render_frame(pattern, reference_camera, 0.25, false, 0);
    std::vector<double> ts, y35, y45;
    for (double t = 10; t <= 230; t += 10) {
      const cv::Mat frame = scene.render_frame(pattern, camera, t, true, 1 + static_cast<std::uint64_t>(t / 10));
      auto evaluated = fusion::evaluate_displacement(reference, frame, evaluator);
      mask_holder(scene, evaluated.field);
      const auto tf = fusion::recover_temperature_field(evaluated.field, demo_geometry(setup), o).field;
      ts.push_back(t), y35.push_back(corrected_probe_c(scene, tf, 0.035, t)), y45.push_back(corrected_probe_c(scene, tf, 0.045, t));
    }
    const double k35 = 100 * (newton_rate(ts, y35, k) / k - 1), k45 = 100 * (newton_rate(ts, y45, k) / k - 1);
    fmt::print("pattern {}: k {:+.3f} % (tc-35mm) {:+.3f} % (tc-45mm)\n", seed, k35, k45);
    sum35 += k35, sum45 += k45, sq35 += k35 * k35, sq45 += k45 * k45;
  }
  const auto se = [&](double sum, double sq) { return std::sqrt((sq - sum * sum / seeds) / (seeds - 1) / seeds); };
  fmt::print("mean ± standard error over {} patterns: {:+.2f} ± {:.2f} % (tc-35mm) {:+.2f} ± {:.2f} % (tc-45mm)\n", seeds,
             sum35 / seeds, se(sum35, sq35), sum45 / seeds, se(sum45, sq45));
}

// One synthetic pair with the demo's camera (512 px square, 3 px dots, blur
// 0.5 px, 8 bits; patterns 100 + pair, noise 200 + pair) under `field`.
SyntheticPair demo_camera_pair(const DisplacementModel& field, int pair, double noise) {
  PairOptions o;
  o.pattern.width_px = 512, o.pattern.height_px = 512, o.pattern.dot_diameter_px = 3;
  o.pattern.seed = 100 + static_cast<std::uint64_t>(pair);
  o.noise_seed = 200 + static_cast<std::uint64_t>(pair);
  o.noise_std = noise, o.blur_sigma_px = 0.5, o.bit_depth = 8;
  o.field = field;
  return render_pair(o);
}

// The evaluator's gain at small uniform shifts u = v = a, the regime of the
// demo's probes (0.025–0.1 px), bounded: the least-squares measured/true
// over the inner vectors of 4 pairs at each of a = ±0.05, ±0.1 px, 1 %
// noise. Measured on 2026-12-04: +0.415 %, standard error over the pairs
// 0.019 % (DISABLED_SmallShiftsThroughTheEvaluator gives +0.32 % at 0.2 px
// to +0.55 ± 0.27 % at 0.0125 px over 8 pairs). The bound, 0 to +0.8 %:
// today's figure ± 0.4 % (about 20 standard errors, room for that spread
// over the amplitudes); it fails if the gain changes sign or doubles — the
// Lanczos-3 deformation gives +1.07 %, the cubic +19 %, two passes +0.22 %.
// A gain error moves each demo probe's k by about as much (issue 29).
TEST(DemoChainBias, TheGainAtSmallUniformShiftsIsWithinTheBound) {
  const fusion::EvaluatorOptions evaluator;  // the defaults
  constexpr int kPairs = 4;
  std::vector<double> gains;  // per pair, over the four shifts
  for (int pair = 0; pair < kPairs; ++pair) {
    double num = 0, den = 0;
    for (const double a : {-0.1, -0.05, 0.05, 0.1}) {
      const SyntheticPair p = demo_camera_pair(DisplacementModel::uniform(a, a), pair, 0.01);
      const auto r = fusion::evaluate_displacement(p.reference, p.measurement, evaluator);
      for (const auto& v : r.field.vectors) {
        if (v.flag != fusion::VectorFlag::kOk || v.x_px < 24 || v.y_px < 24 || v.x_px > 488 || v.y_px > 488) continue;
        num += a * (v.u_px + v.v_px), den += 2 * a * a;
      }
    }
    ASSERT_GT(den, 0);
    gains.push_back(num / den - 1);
  }
  double sum = 0, sq = 0;
  for (const double g : gains) sum += g, sq += g * g;
  const double mean = sum / kPairs, se = std::sqrt(std::max(0.0, sq - sum * sum / kPairs) / (kPairs - 1) / kPairs);
  fmt::print("gain − 1 at small uniform shifts: {:+.3f} ± {:.3f} % (standard error over {} pairs)\n", 100 * mean,
             100 * se, kPairs);
  EXPECT_GT(mean, 0.0);
  EXPECT_LT(mean, 0.008);
}

// Diagnostic, not in the suite: the evaluator alone on synthetic pairs with
// the demo's camera (3 px dots, blur 0.5 px, 1 % noise, 8 bits), the
// measured against the true shift as a function of its amplitude: a uniform
// shift (u = v = a) and a sinusoid v = a·sin(2πx/128 px), whose measured
// amplitude is the projection of v on the sine. Pairs
// BOSFUSE_CHAIN_BIAS_PAIRS (default 8); options as BOSFUSE_CHAIN_BIAS_XCORR.
// Run: build/sim/sim_test --gtest_also_run_disabled_tests --gtest_filter='DemoChainBias.DISABLED_SmallShifts*'
TEST(DemoChainBias, DISABLED_SmallShiftsThroughTheEvaluator) {
  const int pairs = std::getenv("BOSFUSE_CHAIN_BIAS_PAIRS") ? std::atoi(std::getenv("BOSFUSE_CHAIN_BIAS_PAIRS")) : 8;
  const double noise = std::getenv("BOSFUSE_CHAIN_BIAS_NOISE") ? std::atof(std::getenv("BOSFUSE_CHAIN_BIAS_NOISE")) : 0.01;
  const fusion::EvaluatorOptions evaluator = switched_options();
  for (const bool sinusoid : {false, true}) {
    for (const double a : {-0.1, -0.05, -0.025, 0.0125, 0.025, 0.05, 0.1, 0.2}) {
      double sum = 0, sq = 0;
      for (int pair = 0; pair < pairs; ++pair) {
        const SyntheticPair p =
            demo_camera_pair(sinusoid ? DisplacementModel::sinusoid(a, 128) : DisplacementModel::uniform(a, a), pair,
                             noise);
        const auto r = fusion::evaluate_displacement(p.reference, p.measurement, evaluator);
        double num = 0, den = 0;  // least squares: measured ≈ m · truth
        for (const auto& v : r.field.vectors) {
          if (v.flag != fusion::VectorFlag::kOk || v.x_px < 24 || v.y_px < 24 || v.x_px > 488 || v.y_px > 488) continue;
          if (sinusoid) {
            const double s = std::sin(2 * M_PI * v.x_px / 128);
            num += v.v_px * s, den += a * s * s;
          } else {
            num += v.u_px + v.v_px, den += 2 * a;
          }
        }
        const double rel = num / den - 1;
        sum += rel, sq += rel * rel;
      }
      const double mean = sum / pairs, se = std::sqrt(std::max(0.0, sq - sum * sum / pairs) / (pairs - 1) / pairs);
      fmt::print("{} a {:+.4f} px: measured/true − 1 = {:+.3f} ± {:.3f} %, bias {:+.6f} px\n",
                 sinusoid ? "sinusoid" : "uniform ", a, 100 * mean, 100 * se, mean * a);
    }
  }
}

}  // namespace
}  // namespace bosfuse::sim
