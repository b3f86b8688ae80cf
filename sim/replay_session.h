#pragma once
// ReplaySession is one replay of a recorded run (sim/replay.h) into a new
// run: it starts a simulated module on loopback for each recorded device,
// creates the new run with the recording's markers, records it with the
// logger until every recorded sample has been served and the last frame is
// due (or the caller's stop flag is set), and stamps what it recorded with
// the recording's times. `bosfuse replay` is one; tests make their own.
// Between construction and run() the new run exists, empty but for its
// markers, so a caller can add to it (the command copies the recorded
// run's processing settings there).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "acquisition/config/experiment_config.h"
#include "acquisition/logger.h"
#include "sim/replay.h"
#include "storage/run_store.h"

namespace bosfuse::sim {

class ReplaySession {
 public:
  // Reads `recorded_run` (what is unsound about it logged as warnings),
  // starts its modules and creates the new run `out`, replayed `speed`
  // times faster. Throws when the run has nothing to replay.
  ReplaySession(const std::filesystem::path& recorded_run, const std::filesystem::path& out, double speed);
  ~ReplaySession();  // ends and joins the watcher of a run() that threw; never throws
  ReplaySession(const ReplaySession&) = delete;
  ReplaySession& operator=(const ReplaySession&) = delete;

  const RecordedRun& recorded() const { return recorded_; }
  const std::filesystem::path& dir() const { return store_.dir(); }  // the new run's folder

  // Records the replay; ends early when `interrupted` is set. Call once.
  acquisition::Logger::Summary run(const std::atomic<bool>& interrupted);

 private:
  std::filesystem::path recorded_run_;
  std::filesystem::path out_;
  double speed_;
  RecordedRun recorded_;
  std::vector<std::unique_ptr<ModbusSimServer>> servers_;
  acquisition::ExperimentConfig config_;
  std::int64_t started_ns_;
  storage::RunStore store_;
  bool ran_ = false;
  std::atomic<bool> stop_{false};  // set by the watcher when all is replayed, or by the interruption
  std::thread watcher_;
};

}  // namespace bosfuse::sim
