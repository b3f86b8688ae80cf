#include "fusion/time_alignment.h"

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
  if (2 * max_offset_s / step_s + 1 > static_cast<double>(kMaxSearchSteps)) {
    return "max_offset_s / step_s is too fine a search (more than 100000 steps)";
  }
  if (min_common_points < 3) return "min_common_points must be at least 3";
  if (!(std::isfinite(resolution_s) && resolution_s >= step_s)) return "resolution_s must be at least step_s";
  return {};
}

OffsetEstimate estimate_clock_offset(std::span<const double> series_time_s, std::span<const double> series_value,
                                     std::span<const double> frame_time_s, std::span<const double> probe_value,
                                     const OffsetSearchOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (frame_time_s.size() != probe_value.size()) throw std::invalid_argument("frame times and probe values differ");
  const int half_steps = static_cast<int>(std::floor(options.max_offset_s / options.step_s));
  std::vector<double> offsets, r2s;
  for (int s = -half_steps; s <= half_steps; ++s) {
    const double offset = s * options.step_s;
    const auto aligned = align_to_frames(series_time_s, series_value, frame_time_s, offset);
    std::size_t used = 0;
    offsets.push_back(offset);
    r2s.push_back(squared_correlation(aligned.value, probe_value, options.min_common_points, used));
  }
  OffsetEstimate estimate;
  std::size_t best = r2s.size();
  for (std::size_t i = 0; i < r2s.size(); ++i) {
    if (std::isfinite(r2s[i]) && (best == r2s.size() || r2s[i] > r2s[best])) best = i;
  }
  if (best == r2s.size()) {
    estimate.message = "no offset in the search leaves enough common, varying points";
    return estimate;
  }
  // Identifiable only if r² falls on both sides: the best r² at least
  // resolution_s away on the worse side must be lower by min_r2_contrast.
  double left = -1, right = -1;
  for (std::size_t i = 0; i < r2s.size(); ++i) {
    if (!std::isfinite(r2s[i])) continue;
    if (offsets[i] <= offsets[best] - options.resolution_s) left = std::max(left, r2s[i]);
    if (offsets[i] >= offsets[best] + options.resolution_s) right = std::max(right, r2s[i]);
  }
  estimate.r2 = r2s[best];
  estimate.r2_contrast = r2s[best] - std::max(left, right);
  estimate.offset_s = offsets[best];
  estimate.at_search_edge = best == 0 || best + 1 == r2s.size();
  if (!estimate.at_search_edge && std::isfinite(r2s[best - 1]) && std::isfinite(r2s[best + 1])) {
    const double a = r2s[best - 1], b = r2s[best], c = r2s[best + 1];
    const double curvature = a - 2 * b + c;
    if (curvature < 0) estimate.offset_s += 0.5 * (a - c) / curvature * options.step_s;
  }
  const auto aligned = align_to_frames(series_time_s, series_value, frame_time_s, estimate.offset_s);
  squared_correlation(aligned.value, probe_value, options.min_common_points, estimate.common_points);
  if (estimate.at_search_edge) {
    estimate.message = "the best offset is at the edge of the search: widen max_offset_s";
    return estimate;
  }
  if (estimate.r2_contrast < options.min_r2_contrast) {
    estimate.message =
        "the fit hardly depends on the offset on at least one side: the record has no feature that fixes it (a "
        "smooth exponential is the same curve at every offset); configure the offset instead";
    return estimate;
  }
  estimate.ok = true;
  return estimate;
}

}  // namespace bosfuse::fusion
