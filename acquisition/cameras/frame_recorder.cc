#include "acquisition/cameras/frame_recorder.h"

#include <cstdio>
#include <stdexcept>

#include "acquisition/clock.h"
#include "acquisition/config/folder_name.h"
#include "acquisition/cameras/frame_png.h"

namespace bosfuse::acquisition {
namespace fs = std::filesystem;
namespace {

constexpr auto kFolderWait = std::chrono::milliseconds(200);  // how often a waiting recorder checks for stop

std::string frame_file_name(std::int64_t index) {
  char text[32];
  std::snprintf(text, sizeof text, "%06lld.png", static_cast<long long>(index));
  return text;
}

}  // namespace

std::string FrameRecorderOptions::Validate() const {
  if (interval < std::chrono::nanoseconds::zero()) return "frame interval must not be negative";
  if (reference_frames < 0) return "reference_frames must not be negative";
  if (recovery_frames < 1) return "recovery_frames must be at least 1";
  return backoff.Validate();
}

FrameRecorder::FrameRecorder(std::unique_ptr<FrameSource> source, std::string name, std::int64_t device_id,
                             fs::path run_dir, storage::RunWriter& writer, FrameRecorderOptions options)
    : DeviceWorker(std::move(name), device_id, writer),
      source_(std::move(source)),
      run_dir_(std::move(run_dir)),
      frame_dir_(fs::path("frames") / this->name()),
      options_(std::move(options)),
      connection_(
          options_.backoff,
          [this](const std::string& kind, const std::string& message) { record_event(kind, message); },
          options_.recovery_frames) {
  if (const std::string problem = folder_name_problem(this->name()); !problem.empty()) {
    throw std::invalid_argument("camera name '" + this->name() + "' " + problem);
  }
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("camera " + this->name() + ": " + problem);
  }
  fs::create_directories(run_dir_ / frame_dir_);
}

FrameRecorder::Stats FrameRecorder::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

bool FrameRecorder::ensure_connected() {
  if (stats().connected) return true;
  const bool connected = connection_.connect([this] { source_->connect(); }, source_->describe());
  std::lock_guard lock(stats_mutex_);
  stats_.connected = connected;
  return connected;
}

bool FrameRecorder::is_reference_now() const {
  std::error_code ignored;
  return stats().frames < options_.reference_frames ||
         (!options_.reference_flag.empty() && fs::exists(options_.reference_flag, ignored));
}

void FrameRecorder::store(const CapturedFrame& frame) {
  const bool reference = frame.is_reference.value_or(is_reference_now());
  const fs::path relative = frame_dir_ / frame_file_name(stats().frames);
  const fs::path partial = run_dir_ / (relative.string() + ".partial.png");
  try {
    write_frame_png(partial, frame.image);
    fs::rename(partial, run_dir_ / relative);
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(partial, ignored);
    record_event("error", "frame from " + frame.origin + " could not be stored: " + e.what());
    std::lock_guard lock(stats_mutex_);
    ++stats_.failures;
    return;
  }
  push(storage::FrameRecord{0, device_id(), frame.t_ns, frame.device_t_ns, relative.generic_string(), frame.image.cols,
                            frame.image.rows, bit_depth_of(frame.image), reference, frame.arrival_ns});
  std::lock_guard lock(stats_mutex_);
  ++stats_.frames;
  if (reference) ++stats_.reference_frames;
}

bool FrameRecorder::take_one(std::chrono::milliseconds wait) {
  std::optional<CapturedFrame> frame;
  try {
    frame = source_->next(wait);
  } catch (const EndOfFrames& e) {
    connection_.settle();
    record_event("stopped", e.what());
    return false;
  } catch (const FrameLost& e) {
    record_notes();
    record_event("error", e.what());
    std::lock_guard lock(stats_mutex_);
    ++stats_.failures;
    return true;
  } catch (const DeviceError& e) {
    record_notes();
    source_->disconnect();
    connection_.failed("disconnect", e.what(), utc_now_ns());
    std::lock_guard lock(stats_mutex_);
    stats_.connected = false;
    ++stats_.failures;
    return true;
  }
  connection_.succeeded();
  if (frame) store(*frame);
  record_notes();
  return true;
}

void FrameRecorder::record_notes() {
  for (const FrameSource::Note& note : source_->take_notes()) {
    record_event(note.kind, note.message);
    if (note.lost_frames > 0) {
      std::lock_guard lock(stats_mutex_);
      stats_.failures += note.lost_frames;
    }
  }
}

void FrameRecorder::loop() {
  record_frames();
  connection_.settle();  // an outage the camera had come out of ends at its first good frame
}

void FrameRecorder::record_frames() {
  const SteadyTime origin = std::chrono::steady_clock::now();
  SteadyTime deadline = origin;
  const bool scheduled = options_.interval > std::chrono::nanoseconds::zero();
  while (wait_until(deadline)) {
    if (!ensure_connected()) {
      deadline = std::chrono::steady_clock::now() + connection_.backoff();
      continue;
    }
    if (!take_one(scheduled ? std::chrono::duration_cast<std::chrono::milliseconds>(options_.interval) : kFolderWait)) {
      std::lock_guard lock(stats_mutex_);
      stats_.finished = true;
      return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (connection_.retrying()) {
      deadline = now + connection_.backoff();
    } else {
      deadline = scheduled ? origin + ((now - origin) / options_.interval + 1) * options_.interval : now;
    }
  }
}

void FrameRecorder::disconnect_device() noexcept { source_->disconnect(); }

}  // namespace bosfuse::acquisition
