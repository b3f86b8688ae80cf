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
  double resolution_s = 0.5;      // offsets closer than this are not told apart
  double min_r2_contrast = 1e-4;  // needed drop of r² at resolution_s on each side

  std::string Validate() const;  // empty when valid
};

struct OffsetEstimate {
  bool ok = false;
  std::string message;  // why not ok
  double offset_s = 0;
  double r2 = 0;                // at the offset
  double r2_contrast = 0;       // best minus the best r² at least resolution_s away on either side
  bool at_search_edge = false;  // the best offset is the search's limit: widen it
  std::size_t common_points = 0;
};

OffsetEstimate estimate_clock_offset(std::span<const double> series_time_s, std::span<const double> series_value,
                                     std::span<const double> frame_time_s, std::span<const double> probe_value,
                                     const OffsetSearchOptions& options = {});

}  // namespace bosfuse::fusion
