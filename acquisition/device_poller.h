#pragma once
// A DevicePoller reads one ThermocoupleSource on its own thread, on a fixed
// schedule: poll k is due at start + k·period (computed, never accumulated,
// so there is no drift over hours). Each poll's samples are stamped with the
// host UTC clock at the midpoint of request and reply and pushed to the
// RunWriter. A failed poll stores timeout samples, records a disconnect event
// and reconnects with exponential backoff; the return is recorded with the
// length of the gap. One dead device never stalls the others: each has its
// own thread, and the shared writer never blocks on a device.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/connection_keeper.h"
#include "acquisition/thermocouple_source.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

class DevicePoller {
 public:
  struct Options {
    std::chrono::nanoseconds period = std::chrono::seconds(1);
    std::chrono::milliseconds backoff_initial{250};
    std::chrono::milliseconds backoff_max{10'000};
    std::optional<std::int64_t> poll_count;  // stop after this many polls (ok or failed)
    std::string Validate() const;
  };

  struct Stats {
    std::int64_t polls_ok = 0;
    std::int64_t polls_failed = 0;
    std::int64_t connect_failures = 0;
    std::int64_t reconnects = 0;
    std::int64_t missed_ticks = 0;  // polls skipped because a poll overran
    bool connected = false;
    std::vector<storage::Sample> last_samples;  // the latest poll, one per channel
  };

  // `channel_ids` are the run store ids of source->channel_infos(), in order.
  DevicePoller(std::unique_ptr<ThermocoupleSource> source, std::int64_t device_id,
               std::vector<std::int64_t> channel_ids, storage::RunWriter& writer, Options options);
  ~DevicePoller();  // stops; never throws
  DevicePoller(const DevicePoller&) = delete;
  DevicePoller& operator=(const DevicePoller&) = delete;

  void start();
  void stop();
  Stats stats() const;
  const std::string& name() const { return name_; }
  const std::vector<storage::ChannelInfo>& channels() const { return channels_; }

 private:
  using SteadyTime = std::chrono::steady_clock::time_point;

  void run();
  bool ensure_connected();
  std::string poll_once();  // empty on success, else why the device failed
  void count_missed_ticks(SteadyTime deadline, SteadyTime next);
  void record_event(const std::string& kind, const std::string& message);
  SteadyTime next_tick_after(SteadyTime now) const;
  bool wait_until(SteadyTime deadline);  // false when stopping

  std::unique_ptr<ThermocoupleSource> source_;
  std::string name_;
  std::int64_t device_id_;
  std::vector<std::int64_t> channel_ids_;
  std::vector<storage::ChannelInfo> channels_;
  storage::RunWriter& writer_;
  Options options_;

  SteadyTime schedule_origin_;
  ConnectionKeeper connection_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  Stats stats_;
  std::thread thread_;
};

}  // namespace bosfuse::acquisition
