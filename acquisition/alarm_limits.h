#pragma once
// AlarmLimits are the optional alarm thresholds of one channel, from its
// `[[devices.channels]]` table (`alarm_low`, `alarm_high`,
// `alarm_rate_per_min`, `alarm_stale_s`; docs/CONFIG.md, "Alarms"). They are
// in the unit the channel is recorded in, so a millivolt channel converted
// with `emf_type` has them in °C. The AlarmMonitor judges samples against
// them; a channel without any is never watched.

#include <optional>
#include <string>

namespace bosfuse::acquisition {

struct AlarmLimits {
  std::optional<double> low;           // a value below it raises "low"
  std::optional<double> high;          // a value above it raises "high"
  std::optional<double> rate_per_min;  // |rate of change| above it (unit per minute) raises "rate"
  std::optional<double> stale_s;       // this long without an ok value raises "stale"

  // What is wrong, and with which key of the experiment file, so the
  // parser and Validate() say it the same way.
  struct Problem {
    std::string key;
    std::string message;
  };

  bool any() const { return low || high || rate_per_min || stale_s; }
  std::optional<Problem> problem() const;
  std::string Validate() const;  // empty when valid, else "key: what is wrong"
};

}  // namespace bosfuse::acquisition
