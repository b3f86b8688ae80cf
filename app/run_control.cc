#include "app/run_control.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <csignal>
#include <stdexcept>

namespace bosfuse::app {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void request_stop(int) { g_stop.store(true); }

}  // namespace

std::atomic<bool>& stop_requested_by_signal() {
  static const bool installed = [] {
    struct sigaction action {};
    action.sa_handler = request_stop;
    action.sa_flags = SA_RESETHAND;  // the next signal gets the default action: ends the process
    sigemptyset(&action.sa_mask);
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
    return true;
  }();
  (void)installed;
  return g_stop;
}

double seconds_per_time_unit(std::string_view unit) {
  if (unit == "s") return 1;
  if (unit == "ms") return 1e-3;
  if (unit == "m" || unit == "min") return 60;
  if (unit == "h") return 3600;
  return 0;
}

std::chrono::nanoseconds parse_duration(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  const std::string unit = text.substr(used);
  const double seconds_per_unit = unit.empty() ? 1 : seconds_per_time_unit(unit);
  if (used == 0 || seconds_per_unit == 0 || !std::isfinite(value) || value <= 0) {
    throw std::invalid_argument("cannot read duration '" + text + "' (examples: 30s, 10m, 1.5h, 250ms)");
  }
  if (unit.empty()) spdlog::warn("duration '{}' has no unit: taken as {} s (say 90s, 10m, 1.5h or 250ms)", text, value);
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(value * seconds_per_unit * 1e9)));
}

}  // namespace bosfuse::app
