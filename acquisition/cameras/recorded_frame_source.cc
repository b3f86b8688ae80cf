#include "acquisition/cameras/recorded_frame_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <thread>

#include "acquisition/clock.h"
#include "acquisition/cameras/image_file.h"
#include "storage/run_paths.h"
#include "storage/run_store.h"

namespace bosfuse::acquisition {

RecordedFrameSource::RecordedFrameSource(RecordedFrames recorded) : recorded_(std::move(recorded)) {}

std::string RecordedFrameSource::describe() const { return "replay of " + recorded_.run_dir.string(); }

void RecordedFrameSource::connect() {
  if (opened_) return;  // a replay resumes where it was, it does not start over
  started_ = std::chrono::steady_clock::now();
  opened_ = true;
}

std::optional<CapturedFrame> RecordedFrameSource::next(std::chrono::milliseconds wait) {
  while (next_ < recorded_.frames.size()) {
    const storage::FrameRecord& record = recorded_.frames[next_];
    const auto due = started_ + std::chrono::nanoseconds(static_cast<std::int64_t>(
                                    static_cast<double>(record.t_ns - recorded_.origin_ns) / recorded_.speed));
    if (due > std::chrono::steady_clock::now() + wait) {
      std::this_thread::sleep_for(wait);
      return std::nullopt;
    }
    std::this_thread::sleep_until(due);
    ++next_;
    CapturedFrame frame;
    try {
      frame.image = read_image_file(storage::resolve_in_run(recorded_.run_dir, record.path));
    } catch (const std::exception& e) {  // a path out of the run, or too many pixels
      spdlog::warn("replay: frame {}: {}; skipped", record.id, e.what());
      ++skipped_;
      continue;
    }
    if (frame.image.empty()) {
      spdlog::warn("replay: frame {} is missing or unreadable; skipped", record.path);
      ++skipped_;
      continue;
    }
    frame.t_ns = utc_now_ns();
    frame.device_t_ns = record.t_ns;
    frame.origin = record.path;
    frame.is_reference = record.is_reference;
    return frame;
  }
  throw EndOfFrames(describe() + ": all frames replayed");
}

RecordedFrames load_recorded_frames(const std::filesystem::path& run_dir, const std::string& camera, double speed) {
  const storage::RunStore store = storage::RunStore::open(run_dir);
  std::optional<std::int64_t> device_id;
  for (const auto& device : store.devices()) {
    if (device.kind == "camera" && device.name == camera) device_id = device.id;
  }
  if (!device_id) throw std::runtime_error(run_dir.string() + " has no camera named '" + camera + "'");
  RecordedFrames recorded{run_dir, {}, store.run().started_ns, speed};
  for (const auto& frame : store.frames()) {
    if (frame.device_id == device_id) recorded.frames.push_back(frame);
  }
  std::stable_sort(recorded.frames.begin(), recorded.frames.end(),
                   [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });
  return recorded;
}

}  // namespace bosfuse::acquisition
