#include "fusion/search_range.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "fusion/window_correlator.h"

namespace bosfuse::fusion {
namespace {

// What one sample of windows of `window_px`, searched within ±bound_px,
// saw: how many were textured and unmasked, how many of those peaked on
// the bound or without a clear peak, and the largest whole-pixel shift of
// the clear ones.
struct SampleResult {
  int textured = 0;
  int unclear = 0;
  int largest_px = 0;
  double unclear_fraction() const { return textured > 0 ? double(unclear) / textured : 0.0; }
};

// Window origins (top-left) in a grid of about `count` spread over `roi`,
// each window with its search (±radius_px) inside it; none when the ROI is
// too small for one.
std::vector<cv::Point> sample_origins(cv::Rect roi, int window_px, int radius_px, int count) {
  const int per_side = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(count)))));
  const int lo_x = roi.x + radius_px, hi_x = roi.x + roi.width - radius_px - window_px;
  const int lo_y = roi.y + radius_px, hi_y = roi.y + roi.height - radius_px - window_px;
  std::vector<cv::Point> origins;
  if (hi_x < lo_x || hi_y < lo_y) return origins;
  auto spread = [per_side](int lo, int hi, int i) {
    return lo + static_cast<int>(std::floor((hi - lo) * (i + 0.5) / per_side));
  };
  for (int j = 0; j < per_side; ++j) {
    for (int i = 0; i < per_side; ++i) origins.emplace_back(spread(lo_x, hi_x, i), spread(lo_y, hi_y, j));
  }
  return origins;
}

bool masked(const cv::Mat& excluded, cv::Rect window, double max_fraction) {
  return !excluded.empty() && cv::countNonZero(excluded(window)) > max_fraction * window.area();
}

// The whole-pixel bound a peak must lie within to be clear: as the first
// pass judges it (XcorrOptions::on_bound_px), half a pixel inside ±bound.
SampleResult sample(const cv::Mat& reference, const cv::Mat& measurement, cv::Rect roi, const cv::Mat& excluded,
                    int window_px, double bound_px, const SearchStart& start, const SearchRangeOptions& options) {
  const int radius_px = static_cast<int>(std::ceil(bound_px)) + 1;
  const double on_bound_px = std::max(bound_px - 0.5, 0.5);
  WindowCorrelator correlator;
  CorrelationPlane plane;
  SampleResult result;
  for (const cv::Point origin : sample_origins(roi, window_px, radius_px, options.sample_windows)) {
    const cv::Rect window(origin, cv::Size(window_px, window_px));
    if (masked(excluded, window, start.max_masked_fraction)) continue;
    const cv::Rect patch(origin.x - radius_px, origin.y - radius_px, window_px + 2 * radius_px,
                         window_px + 2 * radius_px);
    correlator.correlate(reference(window), measurement(patch), radius_px, CorrelationMethod::kAuto, plane);
    if (plane.reference_std < start.min_texture_std) continue;
    ++result.textured;
    const CorrelationPeak peak = find_peak(plane);
    const int shift_px = std::max(std::abs(peak.dx), std::abs(peak.dy));
    if (!(peak.value > 0) || shift_px > on_bound_px || !(peak.ratio >= options.min_peak_ratio)) {
      ++result.unclear;
    } else {
      result.largest_px = std::max(result.largest_px, shift_px);
    }
  }
  return result;
}

// The largest window of a multiple of 8 px, up to `wanted`, whose search of
// a quarter of it fits in the ROI with the window.
int widest_window_px(cv::Rect roi, int wanted) {
  const int side = std::min(roi.width, roi.height);
  int window = std::min(wanted, 128);
  while (window >= 8 && window + 2 * (window / 4 + 1) > side) window -= 8;
  return window - window % 8;
}

int multiple_of_8_at_least(double px) { return 8 * static_cast<int>(std::ceil(px / 8.0)); }

}  // namespace

std::string SearchRangeOptions::Validate() const {
  if (sample_windows < 1 || sample_windows > 4096) return "search sample must be 1 to 4096 windows";
  if (!(widen_fraction >= 0 && widen_fraction <= 1)) return "search widening fraction must be 0 to 1";
  if (!(beyond_reach_fraction >= widen_fraction && beyond_reach_fraction <= 1)) {
    return "search beyond-reach fraction must lie between the widening fraction and 1";
  }
  if (wide_window_px < 8 || wide_window_px > 128) return "wide search window must be 8 to 128 px";
  if (!(margin_px >= 0 && margin_px <= 16)) return "search margin must be 0 to 16 px";
  if (!(min_peak_ratio >= 1) || !std::isfinite(min_peak_ratio)) return "search peak ratio must be at least 1";
  return {};
}

std::string SearchRange::Describe() const {
  if (beyond_reach) {
    return fmt::format(
        "search ±{:g} px, {} px first windows: displacements seem to exceed it, the widest search the scene "
        "allows ({} of {} sampled windows peaked on the ±{:g} px bound or showed no clear peak)",
        max_shift_px, first_window_px, on_bound, sampled, given_max_shift_px);
  }
  if (widened) {
    return fmt::format(
        "search ±{:g} px, {} px first windows, found from the scene ({} of {} sampled windows peaked on the ±{:g} px "
        "bound; largest displacement found {:g} px)",
        max_shift_px, first_window_px, on_bound, sampled, given_max_shift_px, largest_px);
  }
  return fmt::format("search ±{:g} px, {} px first windows ({} of {} sampled windows on the bound)", max_shift_px,
                     first_window_px, on_bound, sampled);
}

SearchRange find_search_range(const cv::Mat& reference, const cv::Mat& measurement, cv::Rect roi,
                              const cv::Mat& excluded, const SearchStart& start, const SearchRangeOptions& options) {
  CV_Assert(reference.type() == CV_32FC1 && measurement.type() == CV_32FC1 && reference.size() == measurement.size());
  SearchRange range;
  range.given_max_shift_px = range.max_shift_px = start.max_shift_px;
  range.first_window_px = start.first_window_px;
  const SampleResult given =
      sample(reference, measurement, roi, excluded, start.first_window_px, start.max_shift_px, start, options);
  range.sampled = given.textured;
  range.on_bound = given.unclear;
  if (given.textured == 0 || given.unclear_fraction() <= options.widen_fraction) return range;

  const int wide_window_px = widest_window_px(roi, options.wide_window_px);
  const double wide_bound_px = wide_window_px / 4;
  if (wide_window_px < start.first_window_px || wide_bound_px <= start.max_shift_px) {
    range.beyond_reach = true;  // the scene allows no wider search than the one given
    return range;
  }
  const SampleResult wide =
      sample(reference, measurement, roi, excluded, wide_window_px, wide_bound_px, start, options);
  if (wide.textured == 0 || wide.unclear_fraction() > options.beyond_reach_fraction) {
    range.widened = range.beyond_reach = true;
    range.max_shift_px = wide_bound_px;
    range.first_window_px = wide_window_px;
    return range;
  }
  range.largest_px = wide.largest_px;
  range.max_shift_px = std::clamp(std::ceil(wide.largest_px + options.margin_px), start.max_shift_px, wide_bound_px);
  // No wider than given when the clear peaks lie inside the given bound (the
  // unclear ones were noise, not shifts past it).
  range.widened = range.max_shift_px > start.max_shift_px;
  if (range.widened) {
    range.first_window_px =
        std::clamp(multiple_of_8_at_least(4 * range.max_shift_px), std::max(start.first_window_px, start.window_px),
                   std::max(wide_window_px, start.first_window_px));
  }
  return range;
}

}  // namespace bosfuse::fusion
