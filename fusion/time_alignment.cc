#include "fusion/time_alignment.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kMaxSearchSteps = 100'001;

struct Points {
  std::vector<double> t, y;
};

Points finite_points(std::span<const double> time_s, std::span<const double> value) {
  if (time_s.size() != value.size()) throw std::invalid_argument("time and value series differ in length");
  Points p;
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    if (i > 0 && time_s[i] < time_s[i - 1]) throw std::invalid_argument("series times must be ascending");
    if (std::isfinite(time_s[i]) && std::isfinite(value[i])) {
      p.t.push_back(time_s[i]);
      p.y.push_back(value[i]);
    }
  }
  return p;
}

double interpolate(const Points& p, double t) {
  if (p.t.empty() || !(t >= p.t.front() && t <= p.t.back())) return kNaN;
  const auto upper = std::upper_bound(p.t.begin(), p.t.end(), t);
  if (upper == p.t.end()) return p.y.back();
  const std::size_t j = static_cast<std::size_t>(upper - p.t.begin());
  if (j == 0) return p.y.front();
  const double t0 = p.t[j - 1], t1 = p.t[j];
  return t1 > t0 ? p.y[j - 1] + (p.y[j] - p.y[j - 1]) * (t - t0) / (t1 - t0) : p.y[j];
}

// Squared correlation of the pairs where both are finite; NaN with too few.
double squared_correlation(const std::vector<double>& a, std::span<const double> b, std::size_t min_points,
                           std::size_t& used) {
  double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  used = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i])) continue;
    sa += a[i], sb += b[i], saa += a[i] * a[i], sbb += b[i] * b[i], sab += a[i] * b[i];
    ++used;
  }
  if (used < min_points) return kNaN;
  const double n = static_cast<double>(used);
  const double va = saa - sa * sa / n, vb = sbb - sb * sb / n, cab = sab - sa * sb / n;
  if (!(va > 0 && vb > 0)) return kNaN;
  return cab * cab / (va * vb);
}

}  // namespace

AlignedSeries align_to_frames(std::span<const double> series_time_s, std::span<const double> series_value,
                              std::span<const double> frame_time_s, double camera_offset_s) {
  const Points points = finite_points(series_time_s, series_value);
  AlignedSeries out;
  out.value.reserve(frame_time_s.size());
  for (double t : frame_time_s) {
    const double v = interpolate(points, t + camera_offset_s);
    out.value.push_back(v);
    out.inside.push_back(std::isfinite(v) ? 1 : 0);
    out.outside += std::isfinite(v) ? 0 : 1;
  }
  return out;
}

std::string OffsetSearchOptions::Validate() const {
  if (!(std::isfinite(max_offset_s) && max_offset_s >= 0)) return "max_offset_s must be finite and non-negative";
  if (!(std::isfinite(step_s) && step_s > 0)) return "step_s must be positive";
  if (!(std::isfinite(stability_factor) && stability_factor >= 1)) return "stability_factor must be at least 1";
  if (2 * max_offset_s * stability_factor / step_s + 1 > static_cast<double>(kMaxSearchSteps)) {
    return "stability_factor * max_offset_s / step_s is too fine a search (more than 100000 steps)";
  }
  if (min_common_points < 3) return "min_common_points must be at least 3";
  if (!(std::isfinite(resolution_s) && resolution_s >= step_s)) return "resolution_s must be at least step_s";
  if (!(min_common_fraction >= 0 && min_common_fraction <= 1)) return "min_common_fraction must be in 0..1";
  return {};
}

namespace {

// r² at offsets s·step_s, s = −half_steps..half_steps; NaN where too few
// frames have a thermocouple value.
struct Profile {
  int half_steps = 0;
  std::vector<double> offsets, r2;
};

Profile r2_profile(std::span<const double> series_time_s, std::span<const double> series_value,
                   std::span<const double> frame_time_s, std::span<const double> probe_value, double half_width_s,
                   const OffsetSearchOptions& options) {
  const auto finite_probe = static_cast<double>(
      std::count_if(probe_value.begin(), probe_value.end(), [](double v) { return std::isfinite(v); }));
  const auto needed = std::max(options.min_common_points,
                               static_cast<std::size_t>(std::ceil(options.min_common_fraction * finite_probe)));
  Profile p;
  p.half_steps = static_cast<int>(std::floor(half_width_s / options.step_s + 1e-9));
  for (int s = -p.half_steps; s <= p.half_steps; ++s) {
    const double offset = s * options.step_s;
    const auto aligned = align_to_frames(series_time_s, series_value, frame_time_s, offset);
    std::size_t used = 0;
    p.offsets.push_back(offset);
    p.r2.push_back(squared_correlation(aligned.value, probe_value, needed, used));
  }
  return p;
}

// The index of the largest r² with |offset| ≤ half_steps·step; size() when none.
std::size_t best_within(const Profile& p, int half_steps) {
  std::size_t best = p.r2.size();
  const auto first = static_cast<std::size_t>(p.half_steps - half_steps);
  for (std::size_t i = first; i <= first + 2 * static_cast<std::size_t>(half_steps); ++i) {
    if (std::isfinite(p.r2[i]) && (best == p.r2.size() || p.r2[i] > p.r2[best])) best = i;
  }
  return best;
}

// Where r², walking from `best` in `direction`, first falls below
// `threshold`, linearly interpolated; NaN when it never does (a flat side).
double crossing(const Profile& p, std::size_t best, int direction, double threshold) {
  for (std::size_t i = best;;) {
    if ((direction < 0 && i == 0) || (direction > 0 && i + 1 == p.r2.size())) return kNaN;
    const std::size_t next = direction < 0 ? i - 1 : i + 1;
    if (!std::isfinite(p.r2[next])) return kNaN;
    if (p.r2[next] < threshold) {
      const double fraction = (p.r2[i] - threshold) / (p.r2[i] - p.r2[next]);
      return p.offsets[i] + fraction * (p.offsets[next] - p.offsets[i]);
    }
    i = next;
  }
}

// Best minus the best r² at least resolution_s away on the worse side, within ±half_steps.
double r2_contrast(const Profile& p, std::size_t best, int half_steps, double resolution_s) {
  double left = -1, right = -1;
  const auto first = static_cast<std::size_t>(p.half_steps - half_steps);
  for (std::size_t i = first; i <= first + 2 * static_cast<std::size_t>(half_steps); ++i) {
    if (!std::isfinite(p.r2[i])) continue;
    if (p.offsets[i] <= p.offsets[best] - resolution_s) left = std::max(left, p.r2[i]);
    if (p.offsets[i] >= p.offsets[best] + resolution_s) right = std::max(right, p.r2[i]);
  }
  return p.r2[best] - std::max(left, right);
}

// The profile likelihood's interval (header) at `sigmas`: where 1 − r²
// exceeds (1 − r²_best)(1 + sigmas²/(n − 3)). Its half-width; 0 when it
// does not close on both sides within the profile.
double profile_half_width_s(const Profile& p, std::size_t best, std::size_t n, double sigmas) {
  if (n <= 3) return 0;
  const double threshold = 1 - (1 - p.r2[best]) * (1 + sigmas * sigmas / static_cast<double>(n - 3));
  const double left = crossing(p, best, -1, threshold), right = crossing(p, best, +1, threshold);
  if (!std::isfinite(left) || !std::isfinite(right)) return 0;
  return 0.5 * (right - left);
}

std::string verdict(const OffsetEstimate& e, const OffsetSearchOptions& options) {
  if (e.at_search_edge) return "the best offset is at the edge of the search: widen max_offset_s";
  if (e.r2_contrast < options.min_r2_contrast) {
    return "the fit hardly depends on the offset on at least one side: the record has no feature that fixes it (a "
           "smooth exponential is the same curve at every offset); configure the offset instead";
  }
  if (!(e.offset_std_s > 0)) {
    return fmt::format(
        "the r2 profile is flat: within +-{:g} s it does not fall on both sides of {:.3g} s by 3 times its own "
        "noise (a profile-likelihood interval that does not close); configure the offset instead",
        e.wide_search_s, e.offset_s);
  }
  if (!e.stable) {
    return fmt::format(
        "the answer depends on the search window: +-{:g} s gives {:.3g} s, +-{:g} s gives {:.3g} s; the record has "
        "no one feature that fixes the offset; configure it instead",
        options.max_offset_s, e.offset_s, e.wide_search_s, e.wide_offset_s);
  }
  return {};
}

}  // namespace

OffsetEstimate estimate_clock_offset(std::span<const double> series_time_s, std::span<const double> series_value,
                                     std::span<const double> frame_time_s, std::span<const double> probe_value,
                                     const OffsetSearchOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (frame_time_s.size() != probe_value.size()) throw std::invalid_argument("frame times and probe values differ");
  OffsetEstimate estimate;
  estimate.wide_search_s = options.max_offset_s * options.stability_factor;
  const Profile p = r2_profile(series_time_s, series_value, frame_time_s, probe_value, estimate.wide_search_s, options);
  const int inner = static_cast<int>(std::floor(options.max_offset_s / options.step_s + 1e-9));
  const std::size_t best = best_within(p, inner), wide_best = best_within(p, p.half_steps);
  if (best == p.r2.size()) {
    estimate.message = "no offset in the search leaves enough common, varying points";
    return estimate;
  }
  estimate.r2 = p.r2[best];
  estimate.r2_contrast = r2_contrast(p, best, inner, options.resolution_s);
  estimate.offset_s = p.offsets[best];
  const int s = static_cast<int>(best) - p.half_steps;
  estimate.at_search_edge = s == -inner || s == inner;
  if (!estimate.at_search_edge && std::isfinite(p.r2[best - 1]) && std::isfinite(p.r2[best + 1])) {
    const double a = p.r2[best - 1], b = p.r2[best], c = p.r2[best + 1];
    const double curvature = a - 2 * b + c;
    if (curvature < 0) estimate.offset_s += 0.5 * (a - c) / curvature * options.step_s;
  }
  const auto aligned = align_to_frames(series_time_s, series_value, frame_time_s, estimate.offset_s);
  squared_correlation(aligned.value, probe_value, options.min_common_points, estimate.common_points);
  // Identifiable only if the 3σ interval closes inside the wide search; σ never finer than the grid.
  if (profile_half_width_s(p, best, estimate.common_points, 3) > 0) {
    estimate.offset_std_s =
        std::max(profile_half_width_s(p, best, estimate.common_points, 1), options.step_s / std::sqrt(12.0));
  }
  estimate.wide_offset_s = p.offsets[wide_best];
  const double agree_s = std::max(2 * estimate.offset_std_s, options.resolution_s);
  estimate.stable = std::abs(estimate.wide_offset_s - p.offsets[best]) <= agree_s;
  estimate.message = verdict(estimate, options);
  estimate.ok = estimate.message.empty();
  return estimate;
}

}  // namespace bosfuse::fusion
