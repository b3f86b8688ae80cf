#pragma once
// Shared pieces of the long-running subcommands: Ctrl-C / SIGTERM turned
// into a stop request the libraries can poll, and human durations
// ("90s", "10m", "1.5h", "250ms", or plain seconds).

#include <atomic>
#include <chrono>
#include <string>

namespace bosfuse::app {

// Installs SIGINT and SIGTERM handlers (once) that set the returned flag.
std::atomic<bool>& stop_requested_by_signal();

// Throws std::invalid_argument naming the text on anything it cannot read.
std::chrono::nanoseconds parse_duration(const std::string& text);

}  // namespace bosfuse::app
