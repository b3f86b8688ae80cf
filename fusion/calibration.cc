#include "fusion/calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
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

// 1 − SSR/SST about the unweighted mean of y.
double r_squared(const WeightedPoints& p, double ssr) {
  double mean = 0, sst = 0;
  for (double y : p.y) mean += y / static_cast<double>(p.y.size());
  for (double y : p.y) sst += (y - mean) * (y - mean);
  return sst > 0 ? 1 - ssr / sst : std::numeric_limits<double>::quiet_NaN();
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
  c.r2 = r_squared(p, ssr);
  c.ok = true;
  return c;
}

std::string CalibrationChecks::Validate() const {
  if (min_points < 2) return "min_points must be at least 2";
  if (!(std::isfinite(min_r2) && min_r2 <= 1)) return "min_r2 must be a number up to 1";
  if (!(max_residual_rms_c > 0)) return "max_residual_rms_c must be positive";
  if (!(std::isfinite(min_shift_range_sigmas) && min_shift_range_sigmas >= 0)) {
    return "min_shift_range_sigmas must be finite and non-negative";
  }
  if (!(std::isfinite(shift_noise_floor_px) && shift_noise_floor_px > 0))
    return "shift_noise_floor_px must be positive";
  if (expected_sign != 1 && expected_sign != -1) return "expected_sign must be +1 or -1";
  return {};
}

ShiftUncertainty shift_uncertainty(std::span<const double> sigma_px, const CalibrationChecks& checks) {
  std::vector<double> estimated;
  for (double s : sigma_px) {
    if (std::isfinite(s) && s > 0) estimated.push_back(s);
  }
  if (estimated.empty()) {
    return {checks.shift_noise_floor_px, "the default noise floor, as the probe samples carry no sigma"};
  }
  const auto middle = estimated.begin() + static_cast<std::ptrdiff_t>(estimated.size() / 2);
  std::nth_element(estimated.begin(), middle, estimated.end());
  return {*middle, fmt::format("the probe's median sigma over {} samples", estimated.size())};
}

std::vector<std::string> calibration_problems(const LinearCalibration& fit, const ShiftUncertainty& shift,
                                              const CalibrationChecks& checks) {
  if (const auto problem = checks.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (!fit.ok) return {fit.message};
  std::vector<std::string> problems;
  if (fit.points < checks.min_points) {
    problems.push_back(fmt::format("too few points: {}, at least {} needed", fit.points, checks.min_points));
  }
  if (!(fit.slope * checks.expected_sign > 0)) {
    problems.push_back(fmt::format(
        "the slope {:.4g} degC/px has the wrong sign: {} (hotter air refracts less, so |shift| grows with the "
        "departure from the reference's air), a slope {} 0 is expected",
        fit.slope, checks.expected_sign > 0 ? "for a heated flow" : "for a flow colder than the reference's air",
        checks.expected_sign > 0 ? ">" : "<"));
  }
  if (!(fit.r2 >= checks.min_r2)) {
    problems.push_back(fmt::format("a poor fit: r2 = {:.3g}, at least {:g} needed", fit.r2, checks.min_r2));
  }
  if (!(fit.residual_rms <= checks.max_residual_rms_c)) {
    problems.push_back(fmt::format("a poor fit: residual RMS {:.3g} degC, at most {:g} degC allowed", fit.residual_rms,
                                   checks.max_residual_rms_c));
  }
  const double range = fit.x_max - fit.x_min, needed = checks.min_shift_range_sigmas * shift.sigma_px;
  if (!(range >= needed)) {
    problems.push_back(fmt::format(
        "BOS sees no shift where this thermocouple is: the shift ranges over {:.3g}..{:.3g} px ({:.3g} px), less "
        "than {:g} x the shift's uncertainty {:.3g} px ({})",
        fit.x_min, fit.x_max, range, checks.min_shift_range_sigmas, shift.sigma_px, shift.source));
  }
  return problems;
}

}  // namespace bosfuse::fusion
