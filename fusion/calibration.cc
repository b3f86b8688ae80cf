#include "fusion/calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace bosfuse::fusion {
namespace {

struct WeightedPoints {
  std::vector<double> x, y, w;
  std::size_t rejected = 0;
};

WeightedPoints finite_points(std::span<const double> x, std::span<const double> y, std::span<const double> weights) {
  if (x.size() != y.size() || (!weights.empty() && weights.size() != x.size())) {
    throw std::invalid_argument("calibration: x, y and weights differ in length");
  }
  WeightedPoints p;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double w = weights.empty() ? 1.0 : weights[i];
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]) || !std::isfinite(w) || !(w > 0)) {
      ++p.rejected;
      continue;
    }
    p.x.push_back(x[i]);
    p.y.push_back(y[i]);
    p.w.push_back(w);
  }
  return p;
}

// Weighted sums the normal equations need.
struct Sums {
  double w = 0, wx = 0, wy = 0, wxx = 0, wxy = 0;
};

Sums sums_of(const WeightedPoints& p) {
  Sums s;
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    s.w += p.w[i], s.wx += p.w[i] * p.x[i], s.wy += p.w[i] * p.y[i];
    s.wxx += p.w[i] * p.x[i] * p.x[i], s.wxy += p.w[i] * p.x[i] * p.y[i];
  }
  return s;
}

}  // namespace

std::string CalibrationOptions::Validate() const {
  if (min_points < (through_origin ? 2u : 3u)) return "min_points must exceed the number of parameters";
  return {};
}

std::string LinearCalibration::brief_report() const {
  if (!ok) return "calibration failed: " + message;
  std::string text = fmt::format("calibration: {:.5g} ± {:.2g} degC per unit", slope, slope_std_error);
  if (!through_origin) text += fmt::format(", intercept {:.4g} ± {:.2g} degC", intercept, intercept_std_error);
  return text +
         fmt::format(" ({} points, residual RMS {:.3g} degC, x in {:.4g}..{:.4g})", points, residual_rms, x_min, x_max);
}

LinearCalibration fit_linear_calibration(std::span<const double> x, std::span<const double> y,
                                         std::span<const double> weights, const CalibrationOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  const WeightedPoints p = finite_points(x, y, weights);
  LinearCalibration c;
  c.through_origin = options.through_origin;
  c.points = p.x.size();
  c.rejected_non_finite = p.rejected;
  if (c.points < options.min_points) {
    c.message = fmt::format("{} usable points, at least {} needed", c.points, options.min_points);
    return c;
  }
  c.x_min = *std::min_element(p.x.begin(), p.x.end());
  c.x_max = *std::max_element(p.x.begin(), p.x.end());
  const Sums s = sums_of(p);
  const double parameters = options.through_origin ? 1 : 2;
  const double det = options.through_origin ? s.wxx : s.w * s.wxx - s.wx * s.wx;
  if (!(det > 1e-300) || c.x_max - c.x_min <= 0) {
    c.message = "the BOS quantity does not vary: nothing to calibrate against";
    return c;
  }
  c.slope = options.through_origin ? s.wxy / s.wxx : (s.w * s.wxy - s.wx * s.wy) / det;
  c.intercept = options.through_origin ? 0.0 : (s.wy - c.slope * s.wx) / s.w;
  double weighted_ssr = 0, ssr = 0;
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    const double r = p.y[i] - c.apply(p.x[i]);
    weighted_ssr += p.w[i] * r * r;
    ssr += r * r;
  }
  const double s2 = weighted_ssr / (static_cast<double>(c.points) - parameters);
  c.slope_std_error = std::sqrt(s2 * (options.through_origin ? 1 / s.wxx : s.w / det));
  c.intercept_std_error = options.through_origin ? 0.0 : std::sqrt(s2 * s.wxx / det);
  c.residual_rms = std::sqrt(ssr / static_cast<double>(c.points));
  c.ok = true;
  return c;
}

}  // namespace bosfuse::fusion
