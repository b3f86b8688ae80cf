#include "acquisition/alarm_limits.h"

#include <cmath>
#include <sstream>

namespace bosfuse::acquisition {
namespace {

// A year: longer than any run, and a stale limit in nanoseconds fits int64.
constexpr double kLongestStaleS = 365.25 * 86400;

std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

}  // namespace

std::optional<AlarmLimits::Problem> AlarmLimits::problem() const {
  for (const auto& [key, value] :
       {std::pair{"alarm_low", low}, std::pair{"alarm_high", high}, std::pair{"alarm_rate_per_min", rate_per_min},
        std::pair{"alarm_stale_s", stale_s}}) {
    if (value && !std::isfinite(*value)) return Problem{key, "expected a finite number"};
  }
  if (low && high && !(*low < *high)) {
    return Problem{"alarm_high", "must be above alarm_low (" + number_text(*low) + ")"};
  }
  if (rate_per_min && !(*rate_per_min > 0)) {
    return Problem{"alarm_rate_per_min", "expected a positive rate of change (the channel's unit per minute)"};
  }
  if (stale_s && !(*stale_s > 0 && *stale_s <= kLongestStaleS)) {
    return Problem{"alarm_stale_s", "expected a number of seconds above 0, at most a year"};
  }
  return std::nullopt;
}

std::string AlarmLimits::Validate() const {
  const auto found = problem();
  return found ? found->key + ": " + found->message : std::string();
}

}  // namespace bosfuse::acquisition
