#include "fitting/sensor_lag.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace bosfuse::fitting {
namespace {

void check_time_constant(double time_constant_s) {
  if (!(time_constant_s >= 0.0 && std::isfinite(time_constant_s))) {
    throw std::invalid_argument("a sensor's time constant must be finite and not negative");
  }
}

// The map (log τ, ΔT, T_amb) → (log τ, ΔT·(1 − kτ_s), T_amb) applied to the covariance.
ParameterCovariance delagged_covariance(const ParameterCovariance& c, double delta_c, double k_tau) {
  const double factor = 1.0 - k_tau;
  // ∂(ΔT·(1 − kτ_s))/∂log τ = ΔT·kτ_s, as k = e^(−log τ).
  const double jacobian[3][3] = {{1, 0, 0}, {delta_c * k_tau, factor, 0}, {0, 0, 1}};
  ParameterCovariance out{};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t j = 0; j < 3; ++j) {
      double sum = 0;
      for (std::size_t a = 0; a < 3; ++a)
        for (std::size_t b = 0; b < 3; ++b) sum += jacobian[i][a] * c[a][b] * jacobian[j][b];
      out[i][j] = sum;
    }
  }
  return out;
}

}  // namespace

NewtonFit delagged(const NewtonFit& lagged, double time_constant_s) {
  check_time_constant(time_constant_s);
  if (!lagged.ok() || time_constant_s == 0.0) return lagged;
  NewtonFit fit = lagged;
  const double k_tau = lagged.k_per_s.value * time_constant_s;
  if (!(k_tau < 1.0)) {
    fit.summary.status = FitStatus::kUnidentifiable;
    fit.summary.message =
        "the sensor's time constant is not shorter than the curve's own (k·τ ≥ 1): its lag cannot "
        "be removed";
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    fit.t0_c = {kNaN, kNaN, kNaN, kNaN, false};
    fit.covariance.reset();
    return fit;
  }
  const double delta_c = lagged.t0_c.value - lagged.ambient_c.value;
  fit.t0_c.value = lagged.ambient_c.value + delta_c * (1.0 - k_tau);
  if (lagged.covariance) {
    fit.covariance = delagged_covariance(*lagged.covariance, delta_c, k_tau);
    const auto& c = *fit.covariance;
    const double variance = lagged.ambient_c.fixed ? c[1][1] : c[1][1] + c[2][2] + 2.0 * c[1][2];
    fit.t0_c.std_error = std::sqrt(std::max(0.0, variance));
  } else {
    fit.t0_c.std_error *= 1.0 - k_tau;  // without correlations, the amplitude's share is all that is known
  }
  const double half_width = fit.summary.t_critical * fit.t0_c.std_error;
  fit.t0_c.low = fit.t0_c.value - half_width;
  fit.t0_c.high = fit.t0_c.value + half_width;
  return fit;
}

CleanSeries delagged(const CleanSeries& lagged, const NewtonFit& fit, double time_constant_s) {
  check_time_constant(time_constant_s);
  if (!fit.ok() || time_constant_s == 0.0) return lagged;
  CleanSeries out = lagged;
  const double k = fit.k_per_s.value;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const double rate = -k * (fit.temperature_at(out.origin_s + out.time_s[i]) - fit.ambient_c.value);
    out.temperature_c[i] += time_constant_s * rate;
  }
  return out;
}

std::optional<LagEstimate> estimate_lag(const CleanSeries& lagged, const NewtonFit& lagged_fit,
                                        const CleanSeries& reference) {
  if (!lagged_fit.ok()) return std::nullopt;
  const double shift_s = reference.origin_s - lagged.origin_s;  // reference's relative time + shift = lagged's
  std::vector<double> rate, difference;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const auto reading = interpolate(lagged, reference.time_s[i] + shift_s);
    if (!reading) continue;
    const double t_abs = reference.origin_s + reference.time_s[i];
    rate.push_back(-lagged_fit.k_per_s.value * (lagged_fit.temperature_at(t_abs) - lagged_fit.ambient_c.value));
    difference.push_back(*reading - reference.temperature_c[i]);
  }
  const std::size_t n = rate.size();
  if (n < 4) return std::nullopt;
  double mean_rate = 0, mean_difference = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mean_rate += rate[i] / static_cast<double>(n);
    mean_difference += difference[i] / static_cast<double>(n);
  }
  double srr = 0, srd = 0;
  for (std::size_t i = 0; i < n; ++i) {
    srr += (rate[i] - mean_rate) * (rate[i] - mean_rate);
    srd += (rate[i] - mean_rate) * (difference[i] - mean_difference);
  }
  if (!(srr > 1e-12 * (mean_rate * mean_rate * static_cast<double>(n) + 1e-300))) return std::nullopt;
  const double slope = srd / srr;  // = −τ
  double ssr = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = difference[i] - mean_difference - slope * (rate[i] - mean_rate);
    ssr += r * r;
  }
  return LagEstimate{-slope, std::sqrt(ssr / static_cast<double>(n - 2) / srr), n};
}

}  // namespace bosfuse::fitting
