#include "acquisition/logger.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <sstream>
#include <thread>

#include "acquisition/clock.h"
#include "acquisition/cameras/genicam_source.h"
#include "acquisition/cameras/recorded_frame_source.h"
#include "acquisition/cameras/video_capture_source.h"
#include "acquisition/cameras/watched_folder_source.h"

namespace bosfuse::acquisition {
namespace {

constexpr auto kStopCheckInterval = std::chrono::milliseconds(20);

// One per channel, or none when no channel has limits.
template <typename Channel>
std::vector<AlarmLimits> alarm_limits_of(const std::vector<Channel>& channels) {
  std::vector<AlarmLimits> limits;
  for (const Channel& c : channels) limits.push_back(c.alarms);
  const bool any = std::any_of(limits.begin(), limits.end(), [](const AlarmLimits& l) { return l.any(); });
  return any ? limits : std::vector<AlarmLimits>{};
}

}  // namespace

std::string Logger::Summary::BriefReport() const {
  std::ostringstream out;
  out << "logged " << writer.samples_committed << " samples, " << writer.frames_committed << " frames and "
      << writer.events_committed << " events in " << elapsed_s << " s";
  for (const DeviceSummary& d : devices) {
    out << "\n  " << d.name << ": " << d.stats.polls_ok << " polls ok, " << d.stats.polls_failed << " failed, "
        << d.stats.reconnects << " reconnects";
    if (d.stats.connect_failures > 0) out << ", " << d.stats.connect_failures << " failed connection attempts";
    if (d.stats.missed_ticks > 0) out << ", " << d.stats.missed_ticks << " polls skipped (device too slow)";
    if (d.abandoned) out << ", its last read was abandoned at the stop";
  }
  for (const CameraSummary& c : cameras) {
    out << "\n  " << c.name << ": " << c.stats.frames << " frames (" << c.stats.reference_frames << " reference)";
    if (c.stats.failures > 0) out << ", " << c.stats.failures << " failures";
    if (c.stats.finished) out << ", source ended";
    if (c.abandoned) out << ", its last capture was abandoned at the stop";
  }
  if (writer.outages > 0) {
    out << "\n  the run store could not be written " << writer.outages << (writer.outages == 1 ? " time" : " times")
        << " (" << writer.failed_commits << " commits retried); last: " << writer.last_error;
  }
  if (writer.lost() > 0) {
    out << "\n  ERROR: " << writer.lost() << " records read were never stored (" << writer.samples_lost << " samples";
    if (writer.dropped_queue_full > 0) out << "; " << writer.dropped_queue_full << " dropped while the queue was full";
    out << ")";
    out << ": " << writer.last_error;
    if (writer.reserve_released) out << "; the disk reserve was spent on the run's closing events and status";
  }
  if (!writer.status_written) {
    out << "\n  ERROR: the run's status could not be written (" << writer.status_error
        << "); the next command that opens the run marks it interrupted";
  }
  return out.str();
}

std::string Logger::latest_readings(const std::vector<std::shared_ptr<DevicePoller>>& pollers) {
  std::ostringstream out;
  out.precision(2);
  out << std::fixed;
  for (std::size_t d = 0; d < pollers.size(); ++d) {
    const auto stats = pollers[d]->stats();
    out << (d ? " | " : "") << pollers[d]->name() << ":";
    if (!stats.connected) out << " (disconnected)";
    for (std::size_t c = 0; c < stats.last_samples.size(); ++c) {
      const auto& sample = stats.last_samples[c];
      out << " " << pollers[d]->channels()[c].name << " ";
      if (sample.value) {
        out << *sample.value;
      } else {
        out << storage::to_string(sample.status);
      }
    }
  }
  return out.str();
}

void Logger::wait_for_end(const std::atomic<bool>& stop_requested,
                          const std::vector<std::shared_ptr<DevicePoller>>& pollers, storage::RunWriter& writer) const {
  const auto start = std::chrono::steady_clock::now();
  auto next_progress = start + options_.progress_interval;
  auto next_disk_check = start;
  storage::DiskFillWatch disk(options_.disk);
  while (!stop_requested.load()) {
    const auto now = std::chrono::steady_clock::now();
    if (options_.duration && now - start >= *options_.duration) return;
    if (options_.on_progress && now >= next_progress) {
      options_.on_progress(latest_readings(pollers));
      next_progress += options_.progress_interval;
    }
    if (now >= next_disk_check) {
      watch_disk(disk, writer);
      next_disk_check = now + options_.disk_check_interval;
    }
    std::this_thread::sleep_for(kStopCheckInterval);
  }
}

// A disk filling up is said before it is full, with the time left.
void Logger::watch_disk(storage::DiskFillWatch& watch, storage::RunWriter& writer) const {
  std::optional<storage::DiskFillWatch::Change> change;
  try {
    change = watch.add(std::chrono::steady_clock::now(), storage::free_bytes(store_.dir()));
  } catch (const std::exception& e) {
    spdlog::debug("{}", e.what());  // a file system that cannot say its free space is watched no further
    return;
  }
  if (!change) return;
  writer.push(storage::Event{0, std::nullopt, utc_now_ns(), change->short_of_space ? "disk-low" : "disk-ok",
                             change->message});
  if (options_.on_disk_warning) {
    options_.on_disk_warning(change->message);
  } else {
    spdlog::warn("{}: {}", store_.dir().string(), change->message);
  }
}

Logger::Logger(storage::RunStore& store, LoggerOptions options) : store_(store), options_(std::move(options)) {}

void Logger::add_source(std::unique_ptr<ThermocoupleSource> source, std::chrono::nanoseconds period,
                        std::optional<std::int64_t> poll_count, std::vector<AlarmLimits> alarms) {
  sources_.push_back({std::move(source), period, poll_count, std::move(alarms)});
}

void Logger::add_devices(const ExperimentConfig& config) {
  for (const ModbusDeviceConfig& d : config.modbus_devices) {
    add_source(with_emf_conversion(std::make_unique<ModbusDevice>(d.name, d.profile, d.endpoint, d.channels, d.timeout),
                                   d.emf_inputs),
               d.poll_period, d.poll_count, alarm_limits_of(d.channels));
  }
  for (const HidDeviceConfig& d : config.hid_devices) {
    add_source(with_emf_conversion(std::make_unique<HidDevice>(d.name, d.profile, d.match, d.protocol, d.timeout),
                                   d.emf_inputs),
               d.poll_period, d.poll_count, alarm_limits_of(d.protocol.channels));
  }
  for (const UsbDeviceConfig& d : config.usb_devices) {
    add_source(std::make_unique<UsbTc32Device>(d.name, d.serial, d.channels, d.timeout), d.poll_period, d.poll_count,
               alarm_limits_of(d.channels));
  }
  for (const CameraConfig& c : config.cameras) {
    std::unique_ptr<FrameSource> source;
    if (c.source == "video") {
      source = std::make_unique<VideoCaptureSource>(c.target);
    } else if (c.source == "genicam") {
      source = std::make_unique<GenicamSource>(c.genicam);
    } else if (c.source == "replay") {
      source = std::make_unique<RecordedFrameSource>(load_recorded_frames(c.target, c.replay_camera, c.replay_speed));
    } else {
      source = std::make_unique<WatchedFolderSource>(c.folder);
    }
    FrameRecorderOptions options = c.recorder;
    options.reference_flag = c.reference_flag.is_absolute() ? c.reference_flag : store_.dir() / c.reference_flag;
    add_camera(std::move(source), c.name, options);
  }
}

void Logger::add_camera(std::unique_ptr<FrameSource> source, std::string name, FrameRecorderOptions options) {
  cameras_.push_back({std::move(source), std::move(name), std::move(options)});
}

std::vector<std::shared_ptr<FrameRecorder>> Logger::make_recorders(storage::RunWriter& writer) {
  std::vector<std::shared_ptr<FrameRecorder>> recorders;
  for (PendingCamera& camera : cameras_) {
    const std::int64_t device_id =
        store_.add_device({0, camera.name, "camera", camera.source->kind(), camera.source->describe()});
    camera.options.backoff = {options_.backoff_initial, options_.backoff_max};
    recorders.push_back(std::make_shared<FrameRecorder>(std::move(camera.source), camera.name, device_id, store_.dir(),
                                                        writer, camera.options));
  }
  cameras_.clear();
  return recorders;
}

Logger::Summary Logger::run(const std::atomic<bool>& stop_requested) {
  try {
    return run_devices(stop_requested);
  } catch (...) {
    // Whatever was committed stays; the run says it did not end normally.
    try {
      store_.finish(storage::RunStatus::kInterrupted, utc_now_ns());
    } catch (...) {
    }
    throw;
  }
}

std::vector<std::shared_ptr<DevicePoller>> Logger::make_pollers(storage::RunWriter& writer) {
  std::vector<std::shared_ptr<DevicePoller>> pollers;
  for (PendingSource& pending : sources_) {
    const std::int64_t device_id = store_.add_device(pending.source->device_info());
    std::vector<std::int64_t> channel_ids;
    for (storage::ChannelInfo channel : pending.source->channel_infos()) {
      channel.device_id = device_id;
      channel_ids.push_back(store_.add_channel(channel));
    }
    DevicePollerOptions poll_options{pending.period, options_.backoff_initial, options_.backoff_max,
                                       pending.poll_count};
    poll_options.alarms = std::move(pending.alarms);
    poll_options.on_alarm = options_.on_alarm;
    pollers.push_back(
        std::make_shared<DevicePoller>(std::move(pending.source), device_id, channel_ids, writer, poll_options));
  }
  sources_.clear();
  return pollers;
}

Logger::Summary Logger::run_devices(const std::atomic<bool>& stop_requested) {
  const auto started = std::chrono::steady_clock::now();
  Summary summary;
  storage::RunWriter writer(store_, options_.writer);
  const std::vector<std::shared_ptr<DevicePoller>> pollers = make_pollers(writer);
  const std::vector<std::shared_ptr<FrameRecorder>> recorders = make_recorders(writer);
  writer.push(
      storage::Event{0, std::nullopt, utc_now_ns(), "started",
                     std::to_string(pollers.size()) + " devices, " + std::to_string(recorders.size()) + " cameras"});
  for (const auto& poller : pollers) poller->start();
  for (const auto& recorder : recorders) recorder->start();

  wait_for_end(stop_requested, pollers, writer);

  // Every device is asked at once, so one stuck device costs the grace
  // period once, not once per device.
  for (const auto& poller : pollers) poller->request_stop();
  for (const auto& recorder : recorders) recorder->request_stop();
  const auto deadline = std::chrono::steady_clock::now() + DeviceWorker::kStopGrace;
  for (const auto& poller : pollers) {
    const bool ended = poller->finish_stop(deadline);
    summary.devices.push_back({poller->name(), poller->stats(), !ended});
  }
  for (const auto& recorder : recorders) {
    const bool ended = recorder->finish_stop(deadline);
    summary.cameras.push_back({recorder->name(), recorder->stats(), !ended});
  }
  writer.push(storage::Event{0, std::nullopt, utc_now_ns(), "stopped",
                             stop_requested.load() ? "stop requested" : "duration reached"});
  // Bounded in time and never throws, whatever the store does.
  writer.close_run(utc_now_ns());
  summary.writer = writer.stats();
  summary.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return summary;
}

}  // namespace bosfuse::acquisition
