#pragma once
// The digits a channel's value is printed with, wherever a person reads it
// (an export's value columns, `bosfuse runs`, the report's tables, the live
// page, alarm messages): as many decimals as the channel's resolution
// resolves (0.1 °C: one; 0.01: two; 0.0209, the step of a 16-bit register
// over 0–1370 °C: two; 1 or coarser: none), so a quantised reading is never
// shown to 17 digits. A channel whose resolution is unknown (a run recorded
// before schema 6, a float register, a converted millivolt channel without
// a stated `resolution`) is printed to 6 significant digits, which drops the
// binary noise of a scaled integer and keeps any real thermocouple's
// precision. The stored values (run.sqlite, HDF5) keep every bit.

#include <optional>
#include <string>

namespace bosfuse::storage {

// Decimals for a resolution (> 0); none for an unknown one.
std::optional<int> resolution_decimals(std::optional<double> resolution);

// `value` at the channel's digits: "23.4" for 23.400000000000002 at 0.1;
// "nan"/"inf" are never produced — a value that is not finite gives "".
std::string format_channel_value(double value, std::optional<double> resolution);

}  // namespace bosfuse::storage
