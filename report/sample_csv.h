#pragma once
// The samples CSV: what `bosfuse export RUN --csv` writes and `bosfuse fit`
// reads, here together so the two cannot drift apart.
//
// write_samples_csv: one row per poll (samples sharing a timestamp share a
// row), columns `time_utc` (ISO-8601 UTC, the host clock as recorded),
// `t_s` (experiment seconds from the run's origin,
// storage/experiment_clock.h), `time_scale` (experiment seconds per
// recorded second: 16 for a demo recorded 16× fast, 1 for a real run; the
// origin is at time_utc − t_s / time_scale) and one column per channel
// named "NAME [UNIT]"; a cell is empty where a channel had no ok sample then.
// Values are written at their channel's resolution (storage/value_digits.h:
// one decimal for a 0.1 °C channel, 6 significant digits where it is
// unknown); run.sqlite keeps each value as stored.
// The basis is in columns, not in lines above the header, so the file stays
// one table for `bosfuse fit -`, pandas and spreadsheets.
//
// read_csv_series: a time and a temperature column of this file, or of any
// CSV with a header row (spreadsheets, other loggers): times in seconds or
// ISO-8601 UTC (times from ISO-8601 cells are multiplied by the row's
// `time_scale` where the file has one, so they are experiment seconds as
// t_s is), quoted cells, a byte order mark and empty cells handled;
// anything else (a row with more or fewer cells than the header included)
// is an error naming the line.

#include <cstdint>
#include <istream>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "storage/run_store.h"

namespace bosfuse::report {

inline constexpr const char* kTimeScaleColumn = "time_scale";

void write_samples_csv(const storage::RunStore& store, std::ostream& out);

// The two columns as numbers: times in seconds — as written when the column
// holds seconds, relative to the earliest time when it holds ISO-8601 times
// (subtracted in integer nanoseconds, so no precision is lost to
// epoch-scale doubles).
struct CsvSeries {
  std::string time_name;
  std::string temperature_name;
  std::vector<double> time_s;
  std::vector<double> temperature_c;
  std::optional<std::int64_t> iso_origin_ns;
  // The file's time_scale, applied to ISO-8601 times; none when the file has
  // no such column or its times are seconds already.
  std::optional<double> time_scale;
  std::size_t empty_rows = 0;  // rows with an empty time or temperature cell (not a measurement)
};

// Empty column names choose: time t_s, time_s, t, time or time_utc (else the
// first column); temperature T, T_c, temperature_c, temperature, else the
// only other column. Throws std::runtime_error naming the line or column.
CsvSeries read_csv_series(std::istream& in, const std::string& time_column, const std::string& temperature_column);

// A decimal number filling the whole text (nan and inf included); nothing otherwise.
std::optional<double> parse_number(const std::string& text);

}  // namespace bosfuse::report
