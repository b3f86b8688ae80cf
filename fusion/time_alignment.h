#pragma once
// Thermocouple readings and camera frames are taken at different instants
// and, when the camera stamps its own frames, on different clocks. Time
// alignment puts a thermocouple series onto the frame times so the two can
// be compared point by point.
//
// Convention: a frame stamped t_frame happened at host time
// t_frame + camera_offset_s. align_to_frames() interpolates the
// thermocouple series (host clock) linearly at those times; a frame outside
// the series' span gets no value (flagged, never extrapolated).
//
// estimate_clock_offset() searches offsets in ±max_offset_s for the one
// that best explains the BOS probe series by the interpolated thermocouple
// series through a straight line (largest squared correlation r²), refined
// by a parabola through the best grid point and its neighbours. A smooth
// exponential decay cannot fix an offset (shifting it in time only rescales
// it, which the line absorbs), so the estimate needs a feature in the record
// — the heater switched off, a draught. When r² hardly varies over the
// search the result says so and is not ok.
//
// The estimate's standard uncertainty comes from the r² profile's peak
// width, read as a profile likelihood: with the probe explained by a line
// in the thermocouple (2 parameters) plus the offset, the residual sum is
// SSR(δ) = SST·(1 − r²(δ)), and the 1σ interval is where it rises by
// SSR_min / (n − 3), i.e. where 1 − r² exceeds (1 − r²_best)(1 + 1/(n − 3)).
// The offset counts as fixed by the record only when the 3σ interval
// (9 times that rise) closes on both sides inside the wide search below; a
// profile that does not fall that far is flat: not ok. (r² at different
// offsets rests on slightly different frames, those with a thermocouple
// value; a frame dropping out moves r² by about its noise, which the 3σ
// margin keeps from passing for a peak.) The answer must also be stable across search windows: the profile is
// searched over ±stability_factor·max_offset_s as well, and when the best
// offset there is another peak than the one inside ±max_offset_s, the
// estimate is not ok and says both (the record then has competing features,
// or none). Offsets leaving fewer than min_common_fraction of the frames
// with a thermocouple value do not compete (a few points correlate by chance).
//
// All times are seconds in one time base (e.g. since the run's first frame).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace bosfuse::fusion {

struct AlignedSeries {
  std::vector<double> value;         // NaN where !inside
  std::vector<std::uint8_t> inside;  // 1: frame time within the series' span
  std::size_t outside = 0;           // frames with no value

  bool ok(std::size_t i) const { return inside[i] != 0; }
};

// `series_time_s` ascending (throws std::invalid_argument otherwise, or when
// the spans differ in length); non-finite series values are skipped.
AlignedSeries align_to_frames(std::span<const double> series_time_s, std::span<const double> series_value,
                              std::span<const double> frame_time_s, double camera_offset_s = 0);

struct OffsetSearchOptions {
  double max_offset_s = 5;
  double step_s = 0.05;
  std::size_t min_common_points = 5;
  double resolution_s = 0.5;         // offsets closer than this are not told apart
  double min_r2_contrast = 1e-4;     // needed drop of r² at resolution_s on each side
  double stability_factor = 3;       // the answer must be the same over ±this·max_offset_s (1: no check)
  double min_common_fraction = 0.5;  // of the frames, for an offset to compete

  std::string Validate() const;  // empty when valid
};

struct OffsetEstimate {
  bool ok = false;
  std::string message;  // why not ok
  double offset_s = 0;
  double offset_std_s = 0;      // standard uncertainty from the r² profile's width; 0 when not closed
  double r2 = 0;                // at the offset
  double r2_contrast = 0;       // best minus the best r² at least resolution_s away on either side
  bool at_search_edge = false;  // the best offset is the search's limit: widen it
  std::size_t common_points = 0;
  double wide_search_s = 0;  // stability_factor·max_offset_s
  double wide_offset_s = 0;  // the best offset over ±wide_search_s
  bool stable = false;       // the two searches found the same peak
};

OffsetEstimate estimate_clock_offset(std::span<const double> series_time_s, std::span<const double> series_value,
                                     std::span<const double> frame_time_s, std::span<const double> probe_value,
                                     const OffsetSearchOptions& options = {});

}  // namespace bosfuse::fusion
