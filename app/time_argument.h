#pragma once
// A moment of a run named on the command line, for `mark --at`: either a
// UTC time in ISO 8601 (2026-12-01T18:11:29.5Z, or with an offset such as
// +01:00), or a time of the run counted from its first sample with a unit
// (+12.5s, +250ms, +3min, +1h), in experiment seconds, which is what a
// run's exports and reports show when no origin is marked. Use it wherever
// a user names a past moment of a run; the run itself turns an offset into
// its host-clock time (ExperimentClock's scale).

#include <cstdint>
#include <string_view>

namespace bosfuse::app {

struct TimeArgument {
  bool from_first_sample = false;
  std::int64_t utc_ns = 0;  // when !from_first_sample
  double offset_s = 0;      // when from_first_sample: experiment seconds after the first sample
};

// Throws std::invalid_argument saying which forms are understood.
TimeArgument parse_time_argument(std::string_view text);

}  // namespace bosfuse::app
