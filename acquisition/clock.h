#pragma once
// The one host clock every sample and frame is stamped with: nanoseconds
// since the Unix epoch (UTC). Scheduling uses std::chrono::steady_clock
// instead, so a clock step (NTP) never bunches or skips polls.

#include <chrono>
#include <cstdint>
#include <string>

#include "storage/experiment_clock.h"

namespace bosfuse::acquisition {

using storage::utc_now_ns;

// The calendar years a timestamp read from a file may carry. Any two of
// them are less than 292 years apart, so the times and their differences
// fit in int64 nanoseconds; a date outside is a damaged or forged field.
inline constexpr int kEarliestYear = 1900;
inline constexpr int kLatestYear = 2100;
inline constexpr bool plausible_year(int year) { return year >= kEarliestYear && year <= kLatestYear; }

// ISO-8601 UTC, e.g. 2026-11-23T09:13:48.289123Z (storage/experiment_clock.h).
using storage::format_iso8601_utc;

// A compact UTC stamp usable in file names: 20261123T091348Z.
std::string format_compact_utc(std::int64_t t_ns);

}  // namespace bosfuse::acquisition
