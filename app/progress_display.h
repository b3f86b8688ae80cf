#pragma once
// The progress of a long command (process, demo, bench): how many of how
// many items are done, the percentage, the time elapsed and an estimate of
// the time left. On a terminal it is one line rewritten in place; when
// standard error is a file or a pipe (a log, CI) it is one plain line per
// step, flushed as it happens, with no carriage returns or escape codes to
// litter the log. It goes to standard error, never standard output: a
// command's data may be on standard output, piped into another program.
//
// The estimate is the rate since the first step of the current phase
// applied to the items left, so set-up time before the first step does not
// count against the rate; until two steps have been seen it reads "ETA —".
// A step whose total differs, or whose count went back, starts a new phase.
// "elapsed" is the phase's: from the note that announced it (a note while
// no phase runs), else from the display's creation for the first phase.
//
// While a display is on a terminal, messages go through note(), which
// prints them above the progress line instead of in the middle of it.

#include <chrono>
#include <cstddef>
#include <functional>
#include <iostream>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>

namespace bosfuse::app {

class ProgressDisplay {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;

  // On `out` (standard error by default), in place when its file descriptor
  // is a terminal; silent under --quiet (progress and notes are information).
  explicit ProgressDisplay(std::ostream& out = std::cerr);
  // For tests: the mode and the clock are the caller's; never silent.
  ProgressDisplay(std::ostream& out, bool terminal, Clock clock);
  ~ProgressDisplay();  // finish()
  ProgressDisplay(const ProgressDisplay&) = delete;
  ProgressDisplay& operator=(const ProgressDisplay&) = delete;

  // `done` of `total` items are complete; `what` says what is under way.
  void step(std::size_t done, std::size_t total, std::string_view what = {});
  // A message line (a trailing newline is not needed).
  void note(std::string_view line);
  // Ends the in-place line, leaving its last state on the screen.
  void finish();

  // Time left at the rate since the phase's first step; none before two steps.
  std::optional<std::chrono::nanoseconds> eta() const;
  bool terminal() const { return terminal_; }

 private:
  std::optional<std::chrono::nanoseconds> eta_locked() const;
  std::string line_locked() const;
  void draw_locked();

  std::ostream& out_;
  bool terminal_ = false;
  bool silent_ = false;
  std::size_t columns_ = 80;
  Clock clock_;
  // Where the next phase's elapsed time starts: the display's creation, or
  // the note that announced it; none once a phase runs.
  std::optional<std::chrono::steady_clock::time_point> next_phase_origin_;
  // The current phase: where its elapsed time starts, its first step, and
  // the latest one.
  std::chrono::steady_clock::time_point phase_origin_;
  std::chrono::steady_clock::time_point phase_start_;
  std::size_t phase_start_done_ = 0;
  std::chrono::steady_clock::time_point last_time_;
  std::size_t done_ = 0;
  std::size_t total_ = 0;
  std::string what_;
  bool stepped_ = false;
  bool drawn_ = false;  // an unfinished in-place line is on the screen
  // Steps may come from worker threads; one line must not interleave with another.
  mutable std::mutex mutex_;
};

// "0:07", "12:05", "1:02:03": the durations of a progress line.
std::string format_clock_duration(std::chrono::nanoseconds duration);

}  // namespace bosfuse::app
