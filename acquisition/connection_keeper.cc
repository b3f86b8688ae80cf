#include "acquisition/connection_keeper.h"

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

std::string ConnectionKeeper::Backoff::Validate() const {
  if (initial.count() <= 0 || max < initial) return "backoff must be positive and its maximum at least its start";
  return {};
}

ConnectionKeeper::ConnectionKeeper(Backoff backoff, RecordEvent record)
    : limits_(backoff), record_(std::move(record)) {}

bool ConnectionKeeper::connect(const std::function<void()>& connect, const std::string& address) {
  try {
    connect();
  } catch (const DeviceError& e) {
    start_outage("error", std::string(e.what()) + "; retrying", utc_now_ns());
    return false;
  }
  if (!ever_read_ && !in_outage()) record_("connect", "connected to " + address);
  return true;
}

void ConnectionKeeper::failed(const std::string& kind, const std::string& message, std::int64_t at_ns) {
  start_outage(kind, message, at_ns);
}

void ConnectionKeeper::start_outage(const std::string& kind, const std::string& message, std::int64_t at_ns) {
  if (!in_outage()) {
    record_(kind, message);
    outage_since_ns_ = at_ns;
    outage_kind_ = kind;
    backoff_ = limits_.initial;
  } else {
    backoff_ = std::min(backoff_ * 2, limits_.max);
  }
}

ConnectionKeeper::Recovery ConnectionKeeper::succeeded() {
  Recovery recovery = Recovery::kNone;
  if (in_outage()) {
    const std::string gap = seconds_text(utc_now_ns() - outage_since_ns_);
    if (!ever_read_) {
      record_("connect", "connected after " + gap);
      recovery = Recovery::kConnected;
    } else if (outage_kind_ == "bad-reply") {
      record_("recovered", "valid replies again after " + gap);
      recovery = Recovery::kRecovered;
    } else {
      record_("reconnect", "reconnected after " + gap);
      recovery = Recovery::kReconnected;
    }
  }
  ever_read_ = true;
  outage_since_ns_ = 0;
  backoff_ = std::chrono::milliseconds(0);
  return recovery;
}

}  // namespace bosfuse::acquisition
