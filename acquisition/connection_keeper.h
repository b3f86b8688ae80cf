#pragma once
// A ConnectionKeeper keeps one device (a thermocouple reader or a camera)
// connected and says what happened as the events a user reads later. An
// outage starts at the first failure, of connecting or of reading, and ends
// at the first read that works again; it is recorded once at each end (not
// once per retry): "error" (cannot connect), "disconnect" (the link broke)
// or "bad-reply" (the device answers, but not with readings) when it
// starts, and "connect", "reconnect" or "recovered" with its length when it
// ends. While it lasts, attempts are spaced by an exponential backoff. The
// DevicePoller and the FrameRecorder share it so every device behaves the
// same way.
//
// An outage ends only after `recovery_reads` reads in a row have worked
// (a debounce): a device that fails every other poll is one long outage,
// not an event pair per poll. A failure among those reads continues the
// same outage. The end event gives the length of the gap up to the first
// of the good reads and how many attempts failed during the outage
// ("reconnected after 2.150 s (7 failed polls)"). Samples are stored per
// poll whatever the keeper says, so every failed poll stays in the data.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace bosfuse::acquisition {

class ConnectionKeeper {
 public:
  struct Backoff {
    std::chrono::milliseconds initial{250};
    std::chrono::milliseconds max{10'000};
    std::string Validate() const;
  };
  using RecordEvent = std::function<void(const std::string& kind, const std::string& message)>;
  // What a read that worked ended: nothing, the wait for a first connection,
  // a broken link, or a spell of bad replies.
  enum class Recovery { kNone, kConnected, kReconnected, kRecovered };

  // The reads in a row that end an outage; 1 ends it at the first.
  static constexpr int kDefaultRecoveryReads = 1;

  ConnectionKeeper(Backoff backoff, RecordEvent record, int recovery_reads = kDefaultRecoveryReads);

  // Calls `connect` (which throws DeviceError); `address` names the device
  // in the first connect event. After false, wait backoff() before retrying.
  bool connect(const std::function<void()>& connect, const std::string& address);
  // A read failed at `at_ns` (host UTC): `kind` is "disconnect" or "bad-reply".
  void failed(const std::string& kind, const std::string& message, std::int64_t at_ns);
  // A read worked: ends an outage once `recovery_reads` have worked in a row.
  Recovery succeeded();
  // The device is being closed: an outage it had come out of (some good
  // reads, fewer than `recovery_reads`, no failure since) ends at its first
  // good read, so the record does not say it was still failing at the end.
  Recovery settle();

  bool in_outage() const { return outage_since_ns_ != 0; }
  // In an outage and not yet answering again: the next attempt waits backoff().
  bool retrying() const { return in_outage() && good_reads_ == 0; }
  std::chrono::milliseconds backoff() const { return backoff_; }

 private:
  void start_outage(const std::string& kind, const std::string& message, std::int64_t at_ns);
  Recovery end_outage();

  Backoff limits_;
  RecordEvent record_;
  std::chrono::milliseconds backoff_{0};
  int recovery_reads_;
  std::int64_t outage_since_ns_ = 0;
  std::string outage_kind_;
  std::int64_t outage_failures_ = 0;  // failed attempts in this outage
  int good_reads_ = 0;                // reads in a row that worked in this outage
  std::int64_t first_good_ns_ = 0;    // when the first of them was
  bool ever_read_ = false;
};

}  // namespace bosfuse::acquisition
