#pragma once
// The effective averaging width of a displacement evaluator, measured: a
// window-based evaluator returns a field averaged over (about) its window,
// and for a smooth field any averaging kernel with per-axis second moment
// s² returns u + (s²/2)·∇²u, which for a w × w box is u + (w²/24)·∇²u. The
// evaluator's w_eff is the box width with the same second moment,
// w_eff = sqrt(24 · (truth − measured) / ∇²truth). Measured here on
// synthetic dot pairs with a sinusoidal shift v = A·sin(2πx/λ), where
// ∇²v = −(2π/λ)²·v everywhere, so the ratio of measured to true shift (the
// gain g) gives w_eff = sqrt(24·(1 − g)) · λ / 2π. Use it to derive the
// curvature correction of a probe's temperature (fusion/temperature_budget.h)
// for a set of evaluator options, and to check that derivation.

#include <cstdint>
#include <vector>

#include "fusion/displacement_evaluator.h"

namespace bosfuse::sim {

struct WindowResponseCase {
  fusion::EvaluatorOptions evaluator;  // the chain measured; the defaults are the processing's
  int size_px = 256;
  double amplitude_px = 0.5;
  // Long against the window, so that the fourth-order term (w⁴k⁴/1920 for
  // a box) stays below 2 % of the second-order one measured.
  std::vector<double> wavelengths_px{96, 128};
  std::vector<std::uint64_t> seeds{1, 2, 3};
  double noise_std = 0.01;  // fraction of full scale, 8 bit
};

struct WindowResponse {
  double wavelength_px = 0;
  double gain = 0;             // measured / true shift, mean over the seeds
  double gain_std_error = 0;   // of that mean, from the seeds' scatter
  double effective_window_px = 0;
  double effective_window_std_error_px = 0;
  std::size_t vectors = 0;     // valid vectors a window away from the edge, over the seeds
};

// One result per wavelength; throws std::invalid_argument for a case
// without wavelengths, seeds or with fewer than two seeds.
std::vector<WindowResponse> measure_window_response(const WindowResponseCase& c);

// A shift-scale error of the evaluator (a gain g0 ≠ 1 whatever the
// wavelength) would read as curvature at one wavelength; over several,
// g = g0 − κ·k² separates them (least squares, weighted by the gains' σ).
struct CurvatureFit {
  double kappa_px2 = 0;  // w_eff² / 24
  double kappa_std_error_px2 = 0;
  double flat_gain = 1;  // g0
  double effective_window_px() const;  // sqrt(24 κ), 0 for κ ≤ 0
};
// Throws std::invalid_argument for fewer than two wavelengths.
CurvatureFit fit_curvature(const std::vector<WindowResponse>& responses);

}  // namespace bosfuse::sim
