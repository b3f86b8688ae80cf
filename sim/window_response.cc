#include "sim/window_response.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "sim/synthetic_pair.h"

namespace bosfuse::sim {
namespace {

struct Gain {
  double value = 0;
  std::size_t vectors = 0;
};

// Least squares of measured v on true v, through the origin, over valid
// vectors at least a window from the edge (where the windows are whole).
Gain gain_of(const WindowResponseCase& c, double wavelength_px, std::uint64_t seed) {
  PairOptions options;
  options.pattern.width_px = options.pattern.height_px = c.size_px;
  options.pattern.seed = seed;
  options.noise_std = c.noise_std;
  options.noise_seed = seed * 31 + 7;
  options.field = DisplacementModel::sinusoid(c.amplitude_px, wavelength_px);
  const SyntheticPair pair = render_pair(options);
  const auto evaluated = fusion::evaluate_displacement(pair.reference, pair.measurement, c.evaluator);
  const int margin = c.evaluator.xcorr.window_px;
  double sum_mt = 0, sum_tt = 0;
  Gain out;
  for (const auto& v : evaluated.field.vectors) {
    const bool inner =
        v.x_px >= margin && v.y_px >= margin && v.x_px <= c.size_px - margin && v.y_px <= c.size_px - margin;
    if (!v.valid() || !inner) continue;
    const double truth = pair.truth.at(v.x_px, v.y_px).y;
    sum_mt += v.v_px * truth;
    sum_tt += truth * truth;
    ++out.vectors;
  }
  out.value = sum_tt > 0 ? sum_mt / sum_tt : std::nan("");
  return out;
}

}  // namespace

std::vector<WindowResponse> measure_window_response(const WindowResponseCase& c) {
  if (c.wavelengths_px.empty() || c.seeds.size() < 2) {
    throw std::invalid_argument("measure_window_response: at least one wavelength and two seeds");
  }
  std::vector<WindowResponse> out;
  for (const double wavelength : c.wavelengths_px) {
    WindowResponse r;
    r.wavelength_px = wavelength;
    std::vector<double> gains;
    for (const auto seed : c.seeds) {
      const Gain g = gain_of(c, wavelength, seed);
      gains.push_back(g.value);
      r.vectors += g.vectors;
    }
    const double n = static_cast<double>(gains.size());
    double sum = 0, sum_sq = 0;
    for (const double g : gains) sum += g;
    r.gain = sum / n;
    for (const double g : gains) sum_sq += (g - r.gain) * (g - r.gain);
    r.gain_std_error = std::sqrt(sum_sq / (n - 1) / n);
    const double k = 2 * std::numbers::pi / wavelength;
    // w = sqrt(24 (1 − g)) / k; a gain at or above 1 is no measurable
    // averaging (w_eff 0), not an imaginary width.
    const double deficit = std::max(1 - r.gain, 0.0);
    r.effective_window_px = std::sqrt(24 * deficit) / k;
    // dw/dg = −12 / (k² w); at w = 0 the first-order σ is unbounded: take
    // the width that a deficit of one standard error would give.
    r.effective_window_std_error_px = r.effective_window_px > 0
                                          ? 12 * r.gain_std_error / (k * k * r.effective_window_px)
                                          : std::sqrt(24 * r.gain_std_error) / k;
    out.push_back(r);
  }
  return out;
}

double CurvatureFit::effective_window_px() const { return kappa_px2 > 0 ? std::sqrt(24 * kappa_px2) : 0.0; }

CurvatureFit fit_curvature(const std::vector<WindowResponse>& responses) {
  if (responses.size() < 2) throw std::invalid_argument("fit_curvature: at least two wavelengths");
  // Weighted least squares of g on (1, −k²).
  double s = 0, sx = 0, sxx = 0, sy = 0, sxy = 0;
  for (const auto& r : responses) {
    const double k = 2 * std::numbers::pi / r.wavelength_px, x = -k * k;
    const double w = 1 / std::max(r.gain_std_error * r.gain_std_error, 1e-12);
    s += w;
    sx += w * x;
    sxx += w * x * x;
    sy += w * r.gain;
    sxy += w * x * r.gain;
  }
  const double det = s * sxx - sx * sx;
  CurvatureFit fit;
  fit.kappa_px2 = (s * sxy - sx * sy) / det;
  fit.flat_gain = (sxx * sy - sx * sxy) / det;
  fit.kappa_std_error_px2 = std::sqrt(s / det);
  return fit;
}

}  // namespace bosfuse::sim
