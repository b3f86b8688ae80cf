#pragma once
// The Logger records a run: it registers every device and channel in the
// run store, polls each device on its own thread (DevicePoller) and commits
// everything through one RunWriter. It runs until a duration has passed or a
// stop is requested (Ctrl-C), then stops the devices (abandoning, within a
// second, any device call that does not return), commits everything read
// and marks the run complete. A store that cannot be written (full disk,
// I/O error, a lock held by another connection) is an outage the writer
// counts and says, never an exception (see RunWriter); if a record could not
// be committed the run is marked interrupted, with everything committed
// before kept, and the stop stays bounded in time. While it records, the
// logger watches the free space of the run's disk and warns, with the time
// left, when it runs short.

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/device_poller.h"
#include "acquisition/config/experiment_config.h"
#include "storage/disk_space.h"
#include "storage/run_store.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

// What a Logger is set up with.
struct LoggerOptions {
  std::optional<std::chrono::nanoseconds> duration;  // none: until stopped
  storage::RunWriterOptions writer;
  std::chrono::milliseconds backoff_initial{250};
  std::chrono::milliseconds backoff_max{10'000};
  // Called every progress_interval with a one-line account of the latest
  // readings, so a user watching the run sees it is alive.
  std::function<void(const std::string&)> on_progress;
  std::chrono::milliseconds progress_interval{5'000};
  // Called, from the devices' threads, with one line for each alarm raised
  // or cleared ("adam: T1: high 85.2 degC above the limit 80 degC"); the
  // run has them as "alarm" and "alarm-cleared" events either way.
  std::function<void(const std::string&)> on_alarm;
  // Called with one line when the run's disk begins, and ends, to run
  // short of space (also a `disk-low` / `disk-ok` event); unset: a spdlog
  // warning. Checked every disk_check_interval.
  std::function<void(const std::string&)> on_disk_warning;
  std::chrono::milliseconds disk_check_interval{5'000};
  storage::DiskFillWatchOptions disk;
};

class Logger {
 public:
  struct DeviceSummary {
    std::string name;
    DevicePoller::Stats stats;
    bool abandoned = false;  // its last device call was still running at the stop
  };

  struct CameraSummary {
    std::string name;
    FrameRecorder::Stats stats;
    bool abandoned = false;
  };

  struct Summary {
    std::vector<DeviceSummary> devices;
    std::vector<CameraSummary> cameras;
    storage::RunWriter::Stats writer;
    double elapsed_s = 0;
    std::string BriefReport() const;
    // Every record read was committed and the run closed (what a clean stop
    // promises).
    bool complete() const { return writer.lost() == 0 && writer.status_written; }
  };

  Logger(storage::RunStore& store, LoggerOptions options);

  // Adds a device polled every `period`, `poll_count` times when given,
  // its channels watched against `alarms` (one per channel, in
  // channel_infos() order, or none). Call before run().
  void add_source(std::unique_ptr<ThermocoupleSource> source, std::chrono::nanoseconds period,
                  std::optional<std::int64_t> poll_count = std::nullopt, std::vector<AlarmLimits> alarms = {});
  // Adds a camera whose frames are stored under frames/<name>/. Call before run().
  void add_camera(std::unique_ptr<FrameSource> source, std::string name, FrameRecorderOptions options);
  // Adds every device and camera of an experiment file.
  void add_devices(const ExperimentConfig& config);

  Summary run(const std::atomic<bool>& stop_requested);

  // "adam: tc0 78.21 tc1 open-circuit | m7018: (disconnected)"
  static std::string latest_readings(const std::vector<std::shared_ptr<DevicePoller>>& pollers);

 private:
  struct PendingSource {
    std::unique_ptr<ThermocoupleSource> source;
    std::chrono::nanoseconds period;
    std::optional<std::int64_t> poll_count;
    std::vector<AlarmLimits> alarms;
  };

  Summary run_devices(const std::atomic<bool>& stop_requested);
  void wait_for_end(const std::atomic<bool>& stop_requested, const std::vector<std::shared_ptr<DevicePoller>>& pollers,
                    storage::RunWriter& writer) const;
  void watch_disk(storage::DiskFillWatch& watch, storage::RunWriter& writer) const;
  std::vector<std::shared_ptr<DevicePoller>> make_pollers(storage::RunWriter& writer);

  storage::RunStore& store_;
  LoggerOptions options_;
  struct PendingCamera {
    std::unique_ptr<FrameSource> source;
    std::string name;
    FrameRecorderOptions options;
  };

  std::vector<std::shared_ptr<FrameRecorder>> make_recorders(storage::RunWriter& writer);

  std::vector<PendingSource> sources_;
  std::vector<PendingCamera> cameras_;
};

}  // namespace bosfuse::acquisition
