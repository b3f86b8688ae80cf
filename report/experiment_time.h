#pragma once
// Experiment time: the seconds a user reads in an export (DESIGN.md, "Time":
// everything a user reads is in experiment seconds from one origin). For now
// the origin is the run's start (`runs.started_ns`) and a second of the run
// is a second of the experiment. Issue 11 brings a declared origin (an event
// such as "heater off") and the time scale of a simulated or replayed run;
// exports convert through these two functions only, so that change is made
// here.

#include <cstdint>
#include <string>

#include "storage/records.h"

namespace bosfuse::report {

// `t_ns` (host clock, ns since the epoch) in experiment seconds of `run`.
double experiment_time_s(const storage::RunInfo& run, std::int64_t t_ns);

// The origin and scale in words, for files that record their time base, e.g.
// "seconds since the run started (2026-11-18T11:06:40.000Z)".
std::string experiment_time_basis(const storage::RunInfo& run);

}  // namespace bosfuse::report
