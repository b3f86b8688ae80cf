#pragma once
// A ConnectionKeeper keeps one device (a thermocouple reader or a camera)
// connected: it calls the device's connect function, backs off exponentially
// while that fails, and reports what happened as the events a user reads
// later: one "error" per outage (not one per retry), "connect", and
// "reconnect" with the length of the gap. The DevicePoller and the
// FrameRecorder share it so every device behaves the same way.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "storage/run_writer.h"

namespace bosfuse::acquisition {

// Stores a device's event (connect, disconnect, hotplug, ...) in the run and
// logs it, as a warning when something went wrong.
void record_device_event(storage::RunWriter& writer, std::int64_t device_id, const std::string& device_name,
                         const std::string& kind, const std::string& message);

class ConnectionKeeper {
 public:
  struct Backoff {
    std::chrono::milliseconds initial{250};
    std::chrono::milliseconds max{10'000};
    std::string Validate() const;
  };
  using RecordEvent = std::function<void(const std::string& kind, const std::string& message)>;
  enum class Outcome { kConnected, kReconnected, kFailed };

  ConnectionKeeper(Backoff backoff, RecordEvent record);

  // Calls `connect` (which throws DeviceError); `address` names the device in
  // the first connect event. After kFailed, wait backoff() before retrying.
  Outcome connect(const std::function<void()>& connect, const std::string& address);
  // The connection dropped at `since_ns` (host UTC); the next connect is a reconnect.
  void lost(std::int64_t since_ns);
  std::chrono::milliseconds backoff() const { return backoff_; }

 private:
  Backoff limits_;
  RecordEvent record_;
  std::chrono::milliseconds backoff_{0};
  std::int64_t disconnected_since_ns_ = 0;
  bool ever_connected_ = false;
};

}  // namespace bosfuse::acquisition
