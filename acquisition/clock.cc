#include "acquisition/clock.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

namespace bosfuse::acquisition {
namespace {

std::tm utc_fields(std::int64_t seconds) {
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm fields{};
  gmtime_r(&t, &fields);
  return fields;
}

// Floor division, so times before 1970 still split into seconds + fraction.
std::int64_t floor_div(std::int64_t a, std::int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

}  // namespace

std::string format_compact_utc(std::int64_t t_ns) {
  const std::tm f = utc_fields(floor_div(t_ns, 1'000'000'000));
  char text[80];
  std::snprintf(text, sizeof text, "%04d%02d%02dT%02d%02d%02dZ", f.tm_year + 1900, f.tm_mon + 1, f.tm_mday, f.tm_hour,
                f.tm_min, f.tm_sec);
  return text;
}

}  // namespace bosfuse::acquisition
