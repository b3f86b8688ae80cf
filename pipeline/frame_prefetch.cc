#include "pipeline/frame_prefetch.h"

#include <chrono>
#include <stdexcept>
#include <utility>

#include "pipeline/run_selection.h"

namespace bosfuse::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::size_t checked_look_ahead(int look_ahead_frames) {
  if (look_ahead_frames < 0) {
    throw std::invalid_argument("frame prefetch: the look-ahead is " + std::to_string(look_ahead_frames) +
                                " frames; it must be 0 (none) or more");
  }
  return static_cast<std::size_t>(look_ahead_frames);
}

}  // namespace

FramePrefetch::FramePrefetch(std::vector<storage::FrameRecord> frames, Load load, int look_ahead_frames)
    : frames_(std::move(frames)), load_(std::move(load)), look_ahead_(checked_look_ahead(look_ahead_frames)) {
  if (!load_) throw std::invalid_argument("frame prefetch: no function to load a frame with");
  start_loads();
}

FramePrefetch::FramePrefetch(const std::filesystem::path& run_dir, std::vector<storage::FrameRecord> frames,
                             int look_ahead_frames)
    : FramePrefetch(
          std::move(frames), [run_dir](const storage::FrameRecord& frame) { return load_frame(run_dir, frame); },
          look_ahead_frames) {}

// A std::async future waits for its thread when destroyed; clearing them
// here, before load_ and frames_ go, keeps the loads' references valid.
FramePrefetch::~FramePrefetch() { in_flight_.clear(); }

FramePrefetch::Loaded FramePrefetch::load_timed(const storage::FrameRecord& frame) const {
  const auto start = Clock::now();
  cv::Mat image = load_(frame);
  return {std::move(image), seconds_since(start)};
}

void FramePrefetch::start_loads() {
  while (next_to_start_ < frames_.size() && next_to_start_ - next_to_return_ < look_ahead_) {
    const storage::FrameRecord& frame = frames_[next_to_start_];
    in_flight_.push_back(std::async(std::launch::async, [this, &frame] { return load_timed(frame); }));
    ++next_to_start_;  // only once the load runs: std::async may throw
  }
}

std::size_t FramePrefetch::remaining() const { return frames_.size() - next_to_return_; }

std::optional<PrefetchedFrame> FramePrefetch::next() {
  if (next_to_return_ == frames_.size()) return std::nullopt;
  const storage::FrameRecord& frame = frames_[next_to_return_++];
  const auto start = Clock::now();
  if (in_flight_.empty()) {  // no look-ahead: load it here
    ++next_to_start_;
    Loaded loaded = load_timed(frame);
    return PrefetchedFrame{frame, std::move(loaded.image), loaded.seconds, seconds_since(start)};
  }
  std::future<Loaded> pending = std::move(in_flight_.front());
  in_flight_.pop_front();
  start_loads();  // before waiting: the next frame's load overlaps this one's rest too
  Loaded loaded = pending.get();
  return PrefetchedFrame{frame, std::move(loaded.image), loaded.seconds, seconds_since(start)};
}

}  // namespace bosfuse::pipeline
