#include "storage/experiment_clock.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "storage/run_store.h"

namespace bosfuse::storage {
namespace {

// Floor division, so times before 1970 still split into seconds + fraction.
std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

std::string number_text(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

std::int64_t ExperimentClock::to_ns(double t_s) const {
  return origin_ns + static_cast<std::int64_t>(std::llround(t_s / time_scale * 1e9));
}

std::string ExperimentClock::basis() const {
  std::string text = "experiment seconds since " + origin_name + " (" + format_iso8601_utc(origin_ns, 3) + ")";
  if (time_scale != 1) {
    text += "; recorded at " + number_text(time_scale) + "\u00d7 (one second of the record is " +
            number_text(time_scale) + " s of the experiment)";
  }
  return text;
}

ExperimentClock experiment_clock(const RunStore& store) {
  const RunInfo run = store.run();
  ExperimentClock clock;
  clock.time_scale = run.time_scale;
  if (run.origin_event) {
    if (const auto marker = store.marker_ns(*run.origin_event)) {
      clock.origin_ns = *marker;
      clock.origin_name = *run.origin_event;
      return clock;
    }
    clock.note = "the declared origin \"" + *run.origin_event +
                 "\" is not among the run's marker events; t = 0 is the run's first sample";
  }
  clock.origin_name = "the first sample";
  if (const auto first = store.first_sample_ns()) {
    clock.origin_ns = *first;
  } else if (const auto frames = store.frames(); !frames.empty()) {
    clock.origin_ns = frames.front().t_ns;
    clock.origin_name = "the first frame";
  } else {
    clock.origin_ns = run.started_ns;
    clock.origin_name = "the run's start";
  }
  return clock;
}

std::string format_iso8601_utc(std::int64_t t_ns, int fraction_digits) {
  fraction_digits = std::clamp(fraction_digits, 0, 9);
  const std::int64_t seconds = floor_div(t_ns, 1'000'000'000);
  const std::int64_t fraction_ns = t_ns - seconds * 1'000'000'000;
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm f{};
  gmtime_r(&t, &f);
  char text[96];
  int n = std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d", f.tm_year + 1900, f.tm_mon + 1, f.tm_mday,
                        f.tm_hour, f.tm_min, f.tm_sec);
  if (fraction_digits > 0) {
    char digits[16];
    std::snprintf(digits, sizeof digits, "%09lld", static_cast<long long>(fraction_ns));
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n), ".%.*s", fraction_digits, digits);
  }
  std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n), "Z");
  return text;
}

}  // namespace bosfuse::storage
