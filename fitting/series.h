#pragma once
// A temperature time series made ready for computation: samples whose time
// or temperature is NaN or infinite are dropped (and counted, so a caller
// can say how many), the rest are sorted by time, and times are moved to a
// chosen origin. Fits and agreement statistics start from a CleanSeries so
// they never see raw epoch seconds, unsorted data or non-finite values.
//
// A series may carry each sample's standard uncertainty σ (sigma_c), in the
// same order; a fit then weights each sample by 1/σ² (newton_fit.h).
//
// Duplicate times are kept: two readings at one instant are two independent
// measurements of the same temperature, and averaging them would silently
// change their weight in a fit. They are counted so a report can mention
// them.

#include <cstddef>
#include <optional>
#include <span>
#include <vector>

namespace bosfuse::fitting {

struct CleanSeries {
  double origin_s = 0.0;                // absolute time of t = 0, in the caller's time base
  std::vector<double> time_s;           // relative to origin_s, ascending
  std::vector<double> temperature_c;    // same length as time_s
  std::vector<double> sigma_c;          // each sample's standard uncertainty, or empty: not known
  std::size_t rejected_non_finite = 0;  // samples dropped for NaN/inf time or temperature
  std::size_t duplicate_times = 0;      // samples sharing their time with the previous one (kept)

  std::size_t size() const { return time_s.size(); }
  double duration_s() const { return time_s.empty() ? 0.0 : time_s.back() - time_s.front(); }
};

// `time_s` may be epoch-scale seconds: the origin is subtracted in double
// before anything else. The origin defaults to the earliest finite time.
// Throws std::invalid_argument when the two spans differ in length or the
// origin is not finite.
CleanSeries clean_series(std::span<const double> time_s, std::span<const double> temperature_c,
                         std::optional<double> origin_s = std::nullopt);

// The same with each sample's σ, kept beside it: a sample whose σ is NaN or
// infinite is dropped (counted in rejected_non_finite, as it cannot be
// weighted). Throws std::invalid_argument, too, when the σ span differs in
// length or a σ is zero or negative.
CleanSeries clean_series(std::span<const double> time_s, std::span<const double> temperature_c,
                         std::span<const double> sigma_c, std::optional<double> origin_s = std::nullopt);

// Linear interpolation of an ascending series at `t_s` (same origin); nullopt
// outside [front, back]. Duplicate times resolve to the last of them.
std::optional<double> interpolate(const CleanSeries& series, double t_s);

}  // namespace bosfuse::fitting
