#include "view/live_bos.h"

#include <opencv2/imgcodecs.hpp>

#include "view/thread_priority.h"

namespace bosfuse::view {
namespace {

// How long the thread waits for the watch before it looks at stop again.
constexpr auto kWaitLimit = std::chrono::milliseconds(500);
// Frames read per look: more than can arrive between two evaluations.
constexpr int kFramesPerRead = 100'000;

}  // namespace

LiveBos::LiveBos(RunWatch& watch, pipeline::LiveProbeOptions options) : watch_(watch), options_(options) {
  state_.state = "waiting for frames";
  thread_ = std::thread([this] {
    yield_to_the_logger();
    run();
  });
}

LiveBos::~LiveBos() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  watch_.notify();  // ends the thread's wait now rather than at its limit
  if (thread_.joinable()) thread_.join();
}

std::vector<LiveBosResult> LiveBos::results_from(std::size_t index) const {
  std::lock_guard lock(mutex_);
  if (index >= results_.size()) return {};
  return {results_.begin() + static_cast<std::ptrdiff_t>(index), results_.end()};
}

LiveBosState LiveBos::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

std::string LiveBos::latest_frame_png() const {
  std::lock_guard lock(mutex_);
  return latest_png_;
}

void LiveBos::set_state(const std::string& state) {
  {
    std::lock_guard lock(mutex_);
    if (state_.state == state) return;
    state_.state = state;
  }
  watch_.notify();
}

void LiveBos::run() {
  std::optional<storage::RunTail> tail;  // opened at the first frame: a run damaged meanwhile is a state, not a crash
  std::uint64_t seen = 0;
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    const RunSnapshot snapshot = watch_.wait_for_change(seen, kWaitLimit);
    seen = snapshot.generation;
    if (snapshot.head.frame_id <= last_frame_id_) continue;
    try {
      if (!tail) tail.emplace(watch_.run_dir());
      evaluate_new_frames(*tail);
    } catch (const std::exception& e) {
      set_state(e.what());  // tried again with the next frame
    }
  }
}

void LiveBos::evaluate_new_frames(storage::RunTail& tail) {
  if (!probes_) probes_.emplace(watch_.run_dir(), options_);
  const auto fresh = tail.frames_after(last_frame_id_, kFramesPerRead);
  if (fresh.empty()) return;
  last_frame_id_ = fresh.back().id;
  std::vector<storage::FrameRecord> measurements;
  for (const auto& f : fresh) {
    if (!f.is_reference) measurements.push_back(f);
  }
  if (measurements.empty()) return;
  pipeline::LiveFrame frame = probes_->evaluate(measurements.back());
  std::vector<unsigned char> png;
  cv::imencode(".png", frame.thumbnail, png);
  frame.thumbnail.release();
  {
    std::lock_guard lock(mutex_);
    state_.state = "live";
    state_.temperature_source = probes_->temperature_source();
    state_.camera_offset_s = probes_->camera_offset_s();
    state_.skipped += static_cast<std::int64_t>(measurements.size()) - 1;
    ++state_.evaluated;
    results_.push_back({std::move(frame), state_.evaluated, state_.skipped});
    latest_png_.assign(png.begin(), png.end());
  }
  watch_.notify();
}

}  // namespace bosfuse::view
