#pragma once
// An AlarmMonitor judges one device's samples against its channels' alarm
// limits (AlarmLimits, from the experiment file) and says when an alarm
// begins and when it ends: a raise once when its condition begins, a clear
// once when it ends, nothing while it persists, so a run's events and a
// user's terminal are not flooded by a channel that sits above its limit for
// an hour. The rules (docs/CONFIG.md, "Alarms"):
//
// - low / high: an ok value below `low` / above `high`. Cleared only once
//   the value is back inside by a hysteresis of 1% of the limit's magnitude
//   or 0.1 unit, whichever is larger, so a value dithering on a limit does
//   not raise and clear on every poll.
// - rate: the least-squares slope of the ok values of the last 60 s, judged
//   once they span 10 s and number 3 (a slope through every value, not the
//   difference of two, so one noisy reading does not raise it). Cleared
//   when the slope is 1% of the limit below it.
// - stale: no ok value for `stale_s` (failed polls, burnt-out inputs and a
//   disconnected device all count as no value), measured from the monitor's
//   start for a channel that never had one. Only check_stale() raises it;
//   the next ok value clears it.
//
// Samples that are not ok carry no value, so they never raise or clear low,
// high or rate. Pure logic: no clock, threads or I/O; the caller gives every
// time (host UTC nanoseconds, the samples' t_ns) and stores what it returns.

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/alarm_limits.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

enum class AlarmKind { kLow, kHigh, kRate, kStale };
std::string_view to_string(AlarmKind kind);  // "low", "high", "rate", "stale"

// An alarm that began or ended. `message` is the run event's message,
// "<channel>: <kind> <details>", e.g. "T1: high 85.2 degC above the limit
// 80 degC" or "T1: high cleared at 79.1 degC"; readers (the live page) key
// on its "<channel>: <kind>" prefix.
struct AlarmTransition {
  std::int64_t channel_id = 0;
  AlarmKind kind = AlarmKind::kHigh;
  bool raised = true;  // false: cleared
  std::int64_t t_ns = 0;
  std::string message;

  // The run event's kind: "alarm" when raised, "alarm-cleared" when cleared.
  std::string event_kind() const { return raised ? "alarm" : "alarm-cleared"; }
};

class AlarmMonitor {
 public:
  struct Channel {
    std::int64_t id = 0;  // the samples' channel_id
    std::string name;
    std::string unit;  // for the messages
    AlarmLimits limits;
    std::optional<double> resolution = std::nullopt;  // the digits a reading is given with (none: one decimal)
  };

  // Channels without limits are not watched. Throws std::invalid_argument
  // for limits that do not Validate().
  AlarmMonitor(const std::vector<Channel>& channels, std::int64_t start_ns);

  // A sample of a watched channel; others are ignored. `value` counts only
  // with status ok (and when finite).
  std::vector<AlarmTransition> add_sample(std::int64_t channel_id, std::int64_t t_ns, storage::SampleStatus status,
                                          std::optional<double> value);
  // Raises stale for every channel without an ok value for its limit.
  std::vector<AlarmTransition> check_stale(std::int64_t now_ns);

  bool empty() const { return watched_.empty(); }  // no channel has limits
  bool active(std::int64_t channel_id, AlarmKind kind) const;

  // How far inside a low or high limit a value must be to clear it.
  static double hysteresis(double limit);

 private:
  // The ok values of the last 60 s and the sums of their least-squares
  // line, kept as values arrive and leave so a fast poll costs O(1).
  class RateWindow {
   public:
    void add(std::int64_t t_ns, double value);
    // Unit per minute, once the window holds enough to judge.
    std::optional<double> slope_per_min() const;

   private:
    using Point = std::pair<std::int64_t, double>;  // t_ns, value
    void accumulate(const Point& point, double sign);
    void rebase();

    std::deque<Point> points_;
    std::int64_t t0_ns_ = 0;  // sums are of times and values relative to these
    double v0_ = 0;
    double st_ = 0, sv_ = 0, stt_ = 0, stv_ = 0;
    std::size_t dropped_since_rebase_ = 0;
  };

  struct Watched {
    Channel channel;
    std::optional<std::int64_t> last_ok_ns;
    std::array<bool, 4> active{};  // by AlarmKind
    RateWindow window;
  };

  Watched* find(std::int64_t channel_id);
  void judge_limits(Watched& w, std::int64_t t_ns, double value, std::vector<AlarmTransition>& out);
  void judge_rate(Watched& w, std::int64_t t_ns, double value, std::vector<AlarmTransition>& out);
  static void change(Watched& w, AlarmKind kind, bool raise, std::int64_t t_ns, const std::string& details,
                     std::vector<AlarmTransition>& out);

  std::int64_t start_ns_;
  std::vector<Watched> watched_;
};

}  // namespace bosfuse::acquisition
