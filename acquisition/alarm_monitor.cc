#include "acquisition/alarm_monitor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "storage/value_digits.h"

namespace bosfuse::acquisition {
namespace {

constexpr std::int64_t kRateWindowNs = 60'000'000'000;
constexpr std::int64_t kRateShortestSpanNs = 10'000'000'000;
constexpr std::size_t kRateFewestSamples = 3;
constexpr double kRateClearFraction = 0.99;  // a slope 1% under the limit clears it

double seconds(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

std::size_t index(AlarmKind kind) { return static_cast<std::size_t>(kind); }

// One decimal, as a thermocouple is read (85.2, 5.0, 1234.5); three
// significant digits below one (0.450, 0.0123), as a small signal in volts.
std::string value_text(double value) {
  const int magnitude = value == 0 ? 0 : static_cast<int>(std::floor(std::log10(std::fabs(value))));
  const int decimals = magnitude >= 0 ? 1 : std::min(2 - magnitude, 6);
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, value);
  return text;
}

// A reading at its channel's digits where its resolution is known
// (storage/value_digits.h), else as value_text() has it.
std::string reading_text(double value, std::optional<double> resolution) {
  return resolution ? storage::format_channel_value(value, resolution) : value_text(value);
}

// A limit as a user wrote it: 80, 0.5, 12.25.
std::string limit_text(double limit) {
  std::ostringstream text;
  text << limit;
  return text.str();
}

std::string in_unit(const std::string& number, const std::string& unit) {
  return unit.empty() ? number : number + " " + unit;
}

std::string per_minute(const std::string& number, const std::string& unit) {
  return number + " " + (unit.empty() ? std::string("per min") : unit + "/min");
}

std::string gap_text(std::int64_t ns) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f s", seconds(ns));
  return text;
}

}  // namespace

std::string_view to_string(AlarmKind kind) {
  switch (kind) {
    case AlarmKind::kLow:
      return "low";
    case AlarmKind::kHigh:
      return "high";
    case AlarmKind::kRate:
      return "rate";
    case AlarmKind::kStale:
      return "stale";
  }
  return "unknown";
}

void AlarmMonitor::RateWindow::add(std::int64_t t_ns, double value) {
  if (points_.empty()) {
    t0_ns_ = t_ns;
    v0_ = value;
  }
  points_.emplace_back(t_ns, value);
  accumulate(points_.back(), +1);
  while (points_.front().first <= t_ns - kRateWindowNs) {
    accumulate(points_.front(), -1);
    points_.pop_front();
    ++dropped_since_rebase_;
  }
  // Sums kept by adding and subtracting for hours would drift, and times
  // far from t0 lose precision: start afresh each time the window has been
  // replaced, which costs O(1) per sample on average.
  if (dropped_since_rebase_ >= points_.size()) rebase();
}

void AlarmMonitor::RateWindow::rebase() {
  t0_ns_ = points_.front().first;
  v0_ = points_.front().second;
  st_ = sv_ = stt_ = stv_ = 0;
  for (const auto& point : points_) accumulate(point, +1);
  dropped_since_rebase_ = 0;
}

void AlarmMonitor::RateWindow::accumulate(const Point& point, double sign) {
  const double dt = seconds(point.first - t0_ns_);
  const double dv = point.second - v0_;
  st_ += sign * dt;
  sv_ += sign * dv;
  stt_ += sign * dt * dt;
  stv_ += sign * dt * dv;
}

std::optional<double> AlarmMonitor::RateWindow::slope_per_min() const {
  if (points_.size() < kRateFewestSamples) return std::nullopt;
  if (points_.back().first - points_.front().first < kRateShortestSpanNs) return std::nullopt;
  const double n = static_cast<double>(points_.size());
  const double spread = n * stt_ - st_ * st_;
  if (!(spread > 0)) return std::nullopt;
  return (n * stv_ - st_ * sv_) / spread * 60.0;
}

AlarmMonitor::AlarmMonitor(const std::vector<Channel>& channels, std::int64_t start_ns) : start_ns_(start_ns) {
  for (const Channel& c : channels) {
    if (const std::string problem = c.limits.Validate(); !problem.empty()) {
      throw std::invalid_argument("channel " + c.name + ": " + problem);
    }
    if (c.limits.any()) watched_.push_back({c, std::nullopt, {}, {}});
  }
}

double AlarmMonitor::hysteresis(double limit) { return std::max(0.01 * std::fabs(limit), 0.1); }

AlarmMonitor::Watched* AlarmMonitor::find(std::int64_t channel_id) {
  const auto it =
      std::find_if(watched_.begin(), watched_.end(), [&](const Watched& w) { return w.channel.id == channel_id; });
  return it == watched_.end() ? nullptr : &*it;
}

bool AlarmMonitor::active(std::int64_t channel_id, AlarmKind kind) const {
  for (const Watched& w : watched_) {
    if (w.channel.id == channel_id) return w.active[index(kind)];
  }
  return false;
}

void AlarmMonitor::change(Watched& w, AlarmKind kind, bool raise, std::int64_t t_ns, const std::string& details,
                          std::vector<AlarmTransition>& out) {
  w.active[index(kind)] = raise;
  out.push_back(
      {w.channel.id, kind, raise, t_ns, w.channel.name + ": " + std::string(to_string(kind)) + " " + details});
}

void AlarmMonitor::judge_limits(Watched& w, std::int64_t t_ns, double value, std::vector<AlarmTransition>& out) {
  const AlarmLimits& limits = w.channel.limits;
  const std::string& unit = w.channel.unit;
  const std::string cleared = "cleared at " + in_unit(reading_text(value, w.channel.resolution), unit);
  if (limits.high) {
    const bool active = w.active[index(AlarmKind::kHigh)];
    if (!active && value > *limits.high) {
      change(w, AlarmKind::kHigh, true, t_ns,
             in_unit(reading_text(value, w.channel.resolution), unit) + " above the limit " + in_unit(limit_text(*limits.high), unit), out);
    } else if (active && value <= *limits.high - hysteresis(*limits.high)) {
      change(w, AlarmKind::kHigh, false, t_ns, cleared, out);
    }
  }
  if (limits.low) {
    const bool active = w.active[index(AlarmKind::kLow)];
    if (!active && value < *limits.low) {
      change(w, AlarmKind::kLow, true, t_ns,
             in_unit(reading_text(value, w.channel.resolution), unit) + " below the limit " + in_unit(limit_text(*limits.low), unit), out);
    } else if (active && value >= *limits.low + hysteresis(*limits.low)) {
      change(w, AlarmKind::kLow, false, t_ns, cleared, out);
    }
  }
}

void AlarmMonitor::judge_rate(Watched& w, std::int64_t t_ns, double value, std::vector<AlarmTransition>& out) {
  w.window.add(t_ns, value);
  const std::optional<double> slope = w.window.slope_per_min();
  if (!slope) return;  // too little to judge: an alarm stays as it was
  const double limit = *w.channel.limits.rate_per_min;
  const std::string& unit = w.channel.unit;
  const bool active = w.active[index(AlarmKind::kRate)];
  if (!active && std::fabs(*slope) > limit) {
    change(w, AlarmKind::kRate, true, t_ns,
           per_minute(value_text(*slope), unit) + " beyond the limit " + per_minute(limit_text(limit), unit), out);
  } else if (active && std::fabs(*slope) <= limit * kRateClearFraction) {
    change(w, AlarmKind::kRate, false, t_ns, "cleared at " + per_minute(value_text(*slope), unit), out);
  }
}

std::vector<AlarmTransition> AlarmMonitor::add_sample(std::int64_t channel_id, std::int64_t t_ns,
                                                      storage::SampleStatus status, std::optional<double> value) {
  std::vector<AlarmTransition> out;
  Watched* w = find(channel_id);
  if (!w || status != storage::SampleStatus::kOk || !value || !std::isfinite(*value)) return out;
  if (w->active[index(AlarmKind::kStale)]) {
    const std::int64_t gap_ns = t_ns - w->last_ok_ns.value_or(start_ns_);
    change(*w, AlarmKind::kStale, false, t_ns,
           "cleared at " + in_unit(reading_text(*value, w->channel.resolution), w->channel.unit) + " (no value for " + gap_text(gap_ns) + ")",
           out);
  }
  w->last_ok_ns = t_ns;
  judge_limits(*w, t_ns, *value, out);
  if (w->channel.limits.rate_per_min) judge_rate(*w, t_ns, *value, out);
  return out;
}

std::vector<AlarmTransition> AlarmMonitor::check_stale(std::int64_t now_ns) {
  std::vector<AlarmTransition> out;
  for (Watched& w : watched_) {
    if (!w.channel.limits.stale_s || w.active[index(AlarmKind::kStale)]) continue;
    const std::int64_t limit_ns = std::llround(*w.channel.limits.stale_s * 1e9);
    const std::int64_t gap_ns = now_ns - w.last_ok_ns.value_or(start_ns_);
    if (gap_ns > limit_ns) {
      change(w, AlarmKind::kStale, true, now_ns,
             "no value for " + gap_text(gap_ns) + " (limit " + limit_text(*w.channel.limits.stale_s) + " s)", out);
    }
  }
  return out;
}

}  // namespace bosfuse::acquisition
