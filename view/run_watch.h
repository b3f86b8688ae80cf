#pragma once
// RunWatch is the one poller of a viewed run: a thread that looks every
// poll period (100 ms by default) at what the run committed, and wakes the
// live streams when something is new, so idle clients cost no queries. It
// also holds what every stream needs to say about the run — its experiment
// clock (storage/experiment_clock.h), status and device names — and the
// run's description for /api/run. It opens the run read-only; a folder
// that holds no run, or a damaged one, throws storage::StorageError from
// the constructor.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "storage/experiment_clock.h"
#include "storage/run_store.h"
#include "storage/run_tail.h"

namespace bosfuse::view {

using storage::RunTail;
using storage::TailCursor;

struct RunSnapshot {
  std::uint64_t generation = 0;  // grows whenever anything below changed
  TailCursor head;
  std::string status;
  storage::ExperimentClock clock;
  std::map<std::int64_t, std::string> device_names;
};

class RunWatch {
 public:
  RunWatch(const std::filesystem::path& run_dir, std::chrono::milliseconds poll_period);
  ~RunWatch();
  RunWatch(const RunWatch&) = delete;
  RunWatch& operator=(const RunWatch&) = delete;

  const std::filesystem::path& run_dir() const { return run_dir_; }
  RunSnapshot snapshot() const;
  // The snapshot once its generation differs from `seen`, or after `limit`.
  RunSnapshot wait_for_change(std::uint64_t seen, std::chrono::milliseconds limit) const;
  // Wakes every waiter as if the run had changed: another source of the
  // streams' content (view/live_bos.h) has something new.
  void notify();
  // The run's name, status, time basis, channels with units and devices, as JSON text.
  std::string describe_json() const;

 private:
  void poll_until_stopped();
  void poll_once();
  void refresh_description();  // with mutex_ held

  std::filesystem::path run_dir_;
  std::chrono::milliseconds poll_period_;
  storage::RunStore store_;  // used under mutex_ only
  // The experiment file's alarm limits by (device, channel) name: a run's
  // file never changes (an append with another one is refused), so it is
  // read once.
  std::map<std::pair<std::string, std::string>, nlohmann::json> alarm_limits_;
  RunTail tail_;             // the poller thread's own
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  RunSnapshot snapshot_;
  std::chrono::steady_clock::time_point clock_checked_;
  bool stopping_ = false;
  std::thread poller_;  // last: starts once everything above exists
};

}  // namespace bosfuse::view
