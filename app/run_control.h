#pragma once
// Shared pieces of the long-running subcommands: Ctrl-C, SIGTERM and SIGHUP
// (a closed terminal) turned into a stop request the libraries can poll,
// human durations ("90s", "10m", "1.5h", "250ms", or plain seconds), and
// the exit statuses that tell a script what kind of failure it was.

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <string_view>

namespace bosfuse::app {

// Installs SIGINT, SIGTERM and SIGHUP handlers (once) that set the returned
// flag. A second signal ends the process at once (what is committed stays).
std::atomic<bool>& stop_requested_by_signal();

// Exit statuses beyond 0 (success) and 1 (the command failed).
enum ExitStatus : int {
  kExitFailure = 1,
  kExitIncompleteRun = 3,     // the run was recorded, but records read could not be committed
  kExitDeviceSilent = 4,      // the run was recorded, but a device delivered nothing or a camera lost frames
  kExitStopped = 5,           // stopped on request before it finished (process: `--resume` continues)
  kExitSomeFramesFailed = 6,  // evaluate --sequence: the file is written, but some frames could not be evaluated
  kExitRefused = 7,           // calibrate: the result failed its checks and was not stored (--force stores it)
};

// A failure with its own exit status; main() prints the message and exits with it.
class CommandFailure : public std::runtime_error {
 public:
  CommandFailure(ExitStatus status, const std::string& what) : std::runtime_error(what), status_(status) {}
  ExitStatus status() const { return status_; }

 private:
  ExitStatus status_;
};

// Seconds in one ms, s, m (or min) or h; 0 for anything else.
double seconds_per_time_unit(std::string_view unit);

// Throws std::invalid_argument naming the text on anything it cannot read.
// A plain number is seconds, and a warning says it was taken so.
std::chrono::nanoseconds parse_duration(const std::string& text);

}  // namespace bosfuse::app
