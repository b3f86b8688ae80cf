#include "app/time_argument.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

#include "app/run_control.h"

namespace bosfuse::app {
namespace {

[[noreturn]] void refuse(std::string_view text, std::string_view why) {
  throw std::invalid_argument(
      fmt::format("'{}' is not a time of the run ({}): give a UTC time in ISO 8601, e.g. 2026-12-01T18:11:29.5Z, "
                  "or a time from the run's first sample with a unit, e.g. +12.5s (units ms, s, min, h)",
                  text, why));
}

// Digits of a fixed width at `pos`; -1 when they are not there.
int digits(std::string_view text, std::size_t pos, std::size_t width) {
  if (pos + width > text.size()) return -1;
  int value = 0;
  const auto [end, error] = std::from_chars(text.data() + pos, text.data() + pos + width, value);
  return error == std::errc() && end == text.data() + pos + width ? value : -1;
}

bool expect(std::string_view text, std::size_t pos, char c) { return pos < text.size() && text[pos] == c; }

TimeArgument parse_offset(std::string_view text) {
  std::string_view rest = text.substr(1);
  double value = 0;
  const auto [end, error] = std::from_chars(rest.data(), rest.data() + rest.size(), value);
  if (error != std::errc() || end == rest.data()) refuse(text, "no number after '+'");
  const std::string_view unit(end, static_cast<std::size_t>(rest.data() + rest.size() - end));
  const double scale = seconds_per_time_unit(unit);
  if (scale == 0) refuse(text, unit.empty() ? "no unit" : fmt::format("unknown unit '{}'", unit));
  if (!std::isfinite(value * scale)) refuse(text, "not a finite time");
  return {true, 0, value * scale};
}

// Seconds east of UTC of a trailing Z, +hh:mm or -hh:mm at `pos`.
int zone_offset_s(std::string_view text, std::size_t pos) {
  if (pos + 1 == text.size() && text[pos] == 'Z') return 0;
  if (pos + 6 != text.size() || (text[pos] != '+' && text[pos] != '-') || !expect(text, pos + 3, ':'))
    refuse(text, "the time zone must be Z or ±hh:mm");
  const int hours = digits(text, pos + 1, 2), minutes = digits(text, pos + 4, 2);
  if (hours < 0 || hours > 23 || minutes < 0 || minutes > 59) refuse(text, "the time zone must be Z or ±hh:mm");
  return (text[pos] == '-' ? -1 : 1) * (hours * 3600 + minutes * 60);
}

TimeArgument parse_utc(std::string_view text) {
  std::tm tm{};
  tm.tm_year = digits(text, 0, 4) - 1900;
  tm.tm_mon = digits(text, 5, 2) - 1;
  tm.tm_mday = digits(text, 8, 2);
  tm.tm_hour = digits(text, 11, 2);
  tm.tm_min = digits(text, 14, 2);
  tm.tm_sec = digits(text, 17, 2);
  const bool separators = expect(text, 4, '-') && expect(text, 7, '-') && expect(text, 10, 'T') &&
                          expect(text, 13, ':') && expect(text, 16, ':');
  if (!separators || tm.tm_year < 0 || tm.tm_mon < 0 || tm.tm_mon > 11 || tm.tm_mday < 1 || tm.tm_mday > 31 ||
      tm.tm_hour < 0 || tm.tm_hour > 23 || tm.tm_min < 0 || tm.tm_min > 59 || tm.tm_sec < 0 || tm.tm_sec > 60)
    refuse(text, "not YYYY-MM-DDThh:mm:ss");
  std::size_t pos = 19;
  std::int64_t fraction_ns = 0;
  if (expect(text, pos, '.')) {
    std::int64_t scale = 100'000'000;
    for (++pos; pos < text.size() && text[pos] >= '0' && text[pos] <= '9'; ++pos, scale /= 10) {
      if (scale == 0) refuse(text, "more than 9 decimals of a second");
      fraction_ns += (text[pos] - '0') * scale;
    }
  }
  const std::tm asked = tm;
  const std::time_t seconds = timegm(&tm);
  if (tm.tm_mday != asked.tm_mday || tm.tm_mon != asked.tm_mon) refuse(text, "no such day");
  const std::int64_t utc_s = static_cast<std::int64_t>(seconds) - zone_offset_s(text, pos);
  return {false, utc_s * 1'000'000'000 + fraction_ns, 0};
}

}  // namespace

TimeArgument parse_time_argument(std::string_view text) {
  if (text.empty()) refuse(text, "empty");
  if (text.front() == '+') return parse_offset(text);
  return parse_utc(text);
}

}  // namespace bosfuse::app
