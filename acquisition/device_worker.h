#pragma once
// A DeviceWorker is one device's thread in a run: the thermocouple poller
// and the camera recorder are both one. It owns the thread, the stop request
// and how a stop ends. A stop asks the loop to end and waits a grace period
// for it; a loop stuck in a device call that does not return (a read with a
// 20 s timeout, a USB transfer that hangs) is abandoned after that instead
// of holding the whole run hostage: the thread finishes on its own later,
// and from the moment it is abandoned nothing it produces reaches the run.
// Anything the loop throws and does not handle is recorded as an "error"
// event and the loop is restarted after a pause: one device's bug never
// ends the run or the process.
//
// Workers live in a std::shared_ptr (create them with std::make_shared):
// the thread holds a reference, so an abandoned thread never touches a
// destroyed worker.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "storage/run_writer.h"

namespace bosfuse::acquisition {

class DeviceWorker : public std::enable_shared_from_this<DeviceWorker> {
 public:
  using SteadyTime = std::chrono::steady_clock::time_point;
  // How long a stop waits for a device call before abandoning it.
  static constexpr std::chrono::milliseconds kStopGrace{800};

  DeviceWorker(std::string name, std::int64_t device_id, storage::RunWriter& writer);
  virtual ~DeviceWorker();  // never throws; never joins its own thread
  DeviceWorker(const DeviceWorker&) = delete;
  DeviceWorker& operator=(const DeviceWorker&) = delete;

  // Starts the thread; the worker must be owned by a std::shared_ptr.
  void start();
  // Asks the loop to end; returns at once.
  void request_stop() noexcept;
  // Waits until `deadline` for the loop to end; if it has not, abandons it
  // (records an "abandoned" event first). True when the loop ended in time.
  bool finish_stop(SteadyTime deadline) noexcept;
  bool stop(std::chrono::milliseconds grace = kStopGrace) noexcept;

  const std::string& name() const { return name_; }
  std::int64_t device_id() const { return device_id_; }

 protected:
  // The device's loop; returns when stopping() or when the device is done.
  virtual void loop() = 0;
  // Called once when the loop has ended for good (close the device).
  virtual void disconnect_device() noexcept {}

  // Sleeps until `deadline`; false when a stop was requested.
  bool wait_until(SteadyTime deadline);
  bool stopping() const;

  // Everything a worker stores goes through these: once the worker is
  // abandoned they drop what they get, since the writer may be gone.
  void push(std::span<const storage::Sample> samples);
  void push(const storage::FrameRecord& frame);
  // Stores a device event and logs it (a warning when something went wrong).
  void record_event(const std::string& kind, const std::string& message);
  // Stores a device event only, for events the caller reports its own way.
  // False when it was dropped because the worker is abandoned.
  bool store_event(const std::string& kind, const std::string& message);

 private:
  void run() noexcept;

  std::string name_;
  std::int64_t device_id_;
  storage::RunWriter& writer_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;      // stop requested
  std::condition_variable finished_;  // loop ended
  bool stopping_ = false;
  bool ended_ = false;

  std::mutex sink_mutex_;
  bool abandoned_ = false;
  std::thread thread_;
};

}  // namespace bosfuse::acquisition
