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

  ConnectionKeeper(Backoff backoff, RecordEvent record);

  // Calls `connect` (which throws DeviceError); `address` names the device
  // in the first connect event. After false, wait backoff() before retrying.
  bool connect(const std::function<void()>& connect, const std::string& address);
  // A read failed at `at_ns` (host UTC): `kind` is "disconnect" or "bad-reply".
  void failed(const std::string& kind, const std::string& message, std::int64_t at_ns);
  // A read worked: ends an outage, if there was one.
  Recovery succeeded();

  bool in_outage() const { return outage_since_ns_ != 0; }
  std::chrono::milliseconds backoff() const { return backoff_; }

 private:
  void start_outage(const std::string& kind, const std::string& message, std::int64_t at_ns);

  Backoff limits_;
  RecordEvent record_;
  std::chrono::milliseconds backoff_{0};
  std::int64_t outage_since_ns_ = 0;
  std::string outage_kind_;
  bool ever_read_ = false;
};

}  // namespace bosfuse::acquisition
