#pragma once
// The experiment's own time (DESIGN.md, "Time"). A run records host-clock
// nanoseconds; a user reads experiment seconds from one origin:
//
//     t_s = (t_ns − origin_ns) · 1e−9 · time_scale
//
// The origin is the run's declared t = 0 — the first marker event whose
// message the run names as its origin (e.g. "heater off") — else the run's
// first sample (else its first frame, else its start). The scale is the
// run's time scale: a simulation or replay recorded N times faster than the
// experiment happened has N, so its seconds are the experiment's again.
// Every command converts through experiment_clock() and nothing else, so
// there is no second time base anywhere a user can read.

#include <chrono>
#include <cstdint>
#include <string>

namespace bosfuse::storage {

// The host's UTC clock in nanoseconds since the Unix epoch: what every
// sample, frame and event is stamped with.
inline std::int64_t utc_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class RunStore;

struct ExperimentClock {
  std::int64_t origin_ns = 0;
  double time_scale = 1;
  std::string origin_name;  // "heater off", or "the first sample"
  std::string note;         // set when the declared origin was not found, saying what was used instead

  double seconds(std::int64_t t_ns) const { return static_cast<double>(t_ns - origin_ns) * 1e-9 * time_scale; }
  // The host-clock time of experiment second `t_s`.
  std::int64_t to_ns(double t_s) const;
  // One line for axis captions and file headers, e.g. "experiment seconds
  // since heater off (2026-11-30T02:00:00.000Z); recorded at 16× (one second
  // of the record is 16 s of the experiment)".
  std::string basis() const;
};

// The clock of the run `store` holds.
ExperimentClock experiment_clock(const RunStore& store);

// ISO-8601 UTC with `fraction_digits` decimals of a second (0..9), e.g.
// 2026-11-23T09:13:48.289123Z.
std::string format_iso8601_utc(std::int64_t t_ns, int fraction_digits = 6);

}  // namespace bosfuse::storage
