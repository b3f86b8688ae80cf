#include "fitting/series.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace bosfuse::fitting {

namespace {

// `sigma_c` empty: no σ.
CleanSeries clean(std::span<const double> time_s, std::span<const double> temperature_c,
                  std::span<const double> sigma_c, std::optional<double> origin_s) {
  if (time_s.size() != temperature_c.size()) throw std::invalid_argument("time and temperature differ in length");
  const bool with_sigma = !sigma_c.empty();
  if (origin_s && !std::isfinite(*origin_s)) throw std::invalid_argument("the time origin must be finite");
  CleanSeries series;
  std::vector<std::size_t> kept;
  kept.reserve(time_s.size());
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    if (with_sigma && std::isfinite(sigma_c[i]) && !(sigma_c[i] > 0.0)) {
      throw std::invalid_argument("a sample's σ must be positive");
    }
    if (std::isfinite(time_s[i]) && std::isfinite(temperature_c[i]) && (!with_sigma || std::isfinite(sigma_c[i]))) {
      kept.push_back(i);
    } else {
      ++series.rejected_non_finite;
    }
  }
  std::stable_sort(kept.begin(), kept.end(), [&](std::size_t a, std::size_t b) { return time_s[a] < time_s[b]; });
  series.origin_s = origin_s ? *origin_s : (kept.empty() ? 0.0 : time_s[kept.front()]);
  series.time_s.reserve(kept.size());
  series.temperature_c.reserve(kept.size());
  for (std::size_t i : kept) {
    const double t = time_s[i] - series.origin_s;
    if (!series.time_s.empty() && t == series.time_s.back()) ++series.duplicate_times;
    series.time_s.push_back(t);
    series.temperature_c.push_back(temperature_c[i]);
    if (with_sigma) series.sigma_c.push_back(sigma_c[i]);
  }
  return series;
}

}  // namespace

CleanSeries clean_series(std::span<const double> time_s, std::span<const double> temperature_c,
                         std::optional<double> origin_s) {
  return clean(time_s, temperature_c, {}, origin_s);
}

CleanSeries clean_series(std::span<const double> time_s, std::span<const double> temperature_c,
                         std::span<const double> sigma_c, std::optional<double> origin_s) {
  if (sigma_c.size() != time_s.size()) throw std::invalid_argument("σ and time differ in length");
  if (time_s.empty()) return clean(time_s, temperature_c, {}, origin_s);
  return clean(time_s, temperature_c, sigma_c, origin_s);
}

std::optional<double> interpolate(const CleanSeries& series, double t_s) {
  const auto& t = series.time_s;
  if (t.empty() || t_s < t.front() || t_s > t.back()) return std::nullopt;
  const auto upper = std::upper_bound(t.begin(), t.end(), t_s);
  if (upper == t.end()) return series.temperature_c.back();
  const std::size_t hi = static_cast<std::size_t>(upper - t.begin());
  const std::size_t lo = hi - 1;  // hi > 0 because t_s >= t.front()
  const double span = t[hi] - t[lo];
  const double w = span > 0.0 ? (t_s - t[lo]) / span : 0.0;
  return series.temperature_c[lo] + w * (series.temperature_c[hi] - series.temperature_c[lo]);
}

}  // namespace bosfuse::fitting
