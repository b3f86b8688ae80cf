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

std::string failed_polls_text(std::int64_t count) {
  return std::to_string(count) + (count == 1 ? " failed poll" : " failed polls");
}

}  // namespace

std::string ConnectionKeeper::Backoff::Validate() const {
  if (initial.count() <= 0 || max < initial) return "backoff must be positive and its maximum at least its start";
  return {};
}

ConnectionKeeper::ConnectionKeeper(Backoff backoff, RecordEvent record, int recovery_reads)
    : limits_(backoff), record_(std::move(record)), recovery_reads_(std::max(1, recovery_reads)) {}

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
    outage_failures_ = 0;
    backoff_ = limits_.initial;
  } else if (good_reads_ > 0) {
    backoff_ = limits_.initial;  // it had answered again: retry soon, not after a grown backoff
  } else {
    backoff_ = std::min(backoff_ * 2, limits_.max);
  }
  ++outage_failures_;
  good_reads_ = 0;
}

ConnectionKeeper::Recovery ConnectionKeeper::succeeded() {
  if (in_outage()) {
    if (good_reads_++ == 0) first_good_ns_ = utc_now_ns();
    if (good_reads_ < recovery_reads_) return Recovery::kNone;
    return end_outage();
  }
  ever_read_ = true;
  return Recovery::kNone;
}

ConnectionKeeper::Recovery ConnectionKeeper::settle() {
  return in_outage() && good_reads_ > 0 ? end_outage() : Recovery::kNone;
}

ConnectionKeeper::Recovery ConnectionKeeper::end_outage() {
  const std::string gap =
      seconds_text(first_good_ns_ - outage_since_ns_) + " (" + failed_polls_text(outage_failures_) + ")";
  Recovery recovery;
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
  ever_read_ = true;
  outage_since_ns_ = 0;
  good_reads_ = 0;
  backoff_ = std::chrono::milliseconds(0);
  return recovery;
}

}  // namespace bosfuse::acquisition
