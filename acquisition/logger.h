#pragma once
// The Logger records a run: it registers every device and channel in the
// run store, polls each device on its own thread (DevicePoller) and commits
// everything through one RunWriter. It runs until a duration has passed or a
// stop is requested (Ctrl-C), then stops the devices (abandoning, within a
// second, any device call that does not return), commits everything read
// and marks the run complete. If the store itself fails, or a record could
// not be committed, the run is marked interrupted, with everything committed
// before kept.

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/device_poller.h"
#include "acquisition/experiment_config.h"
#include "storage/run_store.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

class Logger {
 public:
  struct Options {
    std::optional<std::chrono::nanoseconds> duration;  // none: until stopped
    storage::RunWriter::Options writer;
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
  };

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
    // Every record read was committed (what a clean stop promises).
    bool complete() const { return writer.uncommitted_at_stop == 0; }
  };

  Logger(storage::RunStore& store, Options options);

  // Adds a device polled every `period`, `poll_count` times when given,
  // its channels watched against `alarms` (one per channel, in
  // channel_infos() order, or none). Call before run().
  void add_source(std::unique_ptr<ThermocoupleSource> source, std::chrono::nanoseconds period,
                  std::optional<std::int64_t> poll_count = std::nullopt, std::vector<AlarmLimits> alarms = {});
  // Adds a camera whose frames are stored under frames/<name>/. Call before run().
  void add_camera(std::unique_ptr<FrameSource> source, std::string name, FrameRecorder::Options options);
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
  void wait_for_end(const std::atomic<bool>& stop_requested,
                    const std::vector<std::shared_ptr<DevicePoller>>& pollers) const;
  std::vector<std::shared_ptr<DevicePoller>> make_pollers(storage::RunWriter& writer);

  storage::RunStore& store_;
  Options options_;
  struct PendingCamera {
    std::unique_ptr<FrameSource> source;
    std::string name;
    FrameRecorder::Options options;
  };

  std::vector<std::shared_ptr<FrameRecorder>> make_recorders(storage::RunWriter& writer);

  std::vector<PendingSource> sources_;
  std::vector<PendingCamera> cameras_;
};

}  // namespace bosfuse::acquisition
