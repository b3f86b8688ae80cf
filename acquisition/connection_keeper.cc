#include "acquisition/connection_keeper.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>

#include "acquisition/clock.h"
#include "acquisition/thermocouple_source.h"

namespace bosfuse::acquisition {
namespace {

std::string seconds_text(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f s", static_cast<double>(ns) * 1e-9);
  return text;
}

}  // namespace

void record_device_event(storage::RunWriter& writer, std::int64_t device_id, const std::string& device_name,
                         const std::string& kind, const std::string& message) {
  writer.push(storage::Event{0, device_id, utc_now_ns(), kind, message});
  if (kind == "disconnect" || kind == "error") {
    spdlog::warn("{}: {}", device_name, message);
  } else {
    spdlog::info("{}: {}", device_name, message);
  }
}

std::string ConnectionKeeper::Backoff::Validate() const {
  if (initial.count() <= 0 || max < initial) return "backoff must be positive and its maximum at least its start";
  return {};
}

ConnectionKeeper::ConnectionKeeper(Backoff backoff, RecordEvent record)
    : limits_(backoff), record_(std::move(record)) {}

ConnectionKeeper::Outcome ConnectionKeeper::connect(const std::function<void()>& connect, const std::string& address) {
  try {
    connect();
  } catch (const DeviceError& e) {
    const bool first_failure = backoff_.count() == 0;
    if (first_failure) {
      record_("error", std::string(e.what()) + "; retrying");
      if (!ever_connected_) disconnected_since_ns_ = utc_now_ns();
    }
    backoff_ = first_failure ? limits_.initial : std::min(backoff_ * 2, limits_.max);
    return Outcome::kFailed;
  }
  backoff_ = std::chrono::milliseconds(0);
  const bool after_gap = disconnected_since_ns_ != 0;
  const bool reconnect = after_gap && ever_connected_;
  if (after_gap) {
    const std::int64_t gap_ns = utc_now_ns() - disconnected_since_ns_;
    record_(reconnect ? "reconnect" : "connect",
            (reconnect ? "reconnected after " : "connected after ") + seconds_text(gap_ns));
  } else {
    record_("connect", "connected to " + address);
  }
  ever_connected_ = true;
  disconnected_since_ns_ = 0;
  return reconnect ? Outcome::kReconnected : Outcome::kConnected;
}

void ConnectionKeeper::lost(std::int64_t since_ns) { disconnected_since_ns_ = since_ns; }

}  // namespace bosfuse::acquisition
