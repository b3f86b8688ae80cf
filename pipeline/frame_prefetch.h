#pragma once
// A run's frames handed out in order, the next ones already decoding on a
// second thread: while the caller evaluates frame N, frame N + 1 is being
// read. Inflating a 16 MP PNG takes 150–300 ms on one core, time the
// evaluation's serial stretches leave a core idle for. Use it where frames
// are worked through in order, each once (process_run); a caller that jumps
// about (the live page) has nothing to read ahead.
//
// The look-ahead is bounded: besides the frame the caller holds, at most
// `look_ahead_frames` are decoded or decoding (a 16 MP 16-bit frame is
// 32 MB). With 0 nothing runs in the background: next() loads the frame on
// the caller's thread. The first frames start loading at construction, so
// they overlap whatever the caller prepares before its first next().
//
// Each frame is loaded exactly once. A load that throws throws from the
// next() that would have returned its frame, with the load's own exception;
// the frames before it come as usual. Destroying the prefetch (the caller
// stops early, or unwinds from an error) waits for the loads in flight — a
// decode cannot be interrupted, so a stop waits for at most one — and drops
// them: no thread outlives it.

#include <cstddef>
#include <deque>
#include <filesystem>
#include <functional>
#include <future>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "storage/records.h"

namespace bosfuse::pipeline {

struct PrefetchedFrame {
  storage::FrameRecord frame;
  cv::Mat image;
  double decode_seconds = 0;  // the load's own time, on whichever thread ran it
  double wait_seconds = 0;    // how long next() held the caller up for it
};

class FramePrefetch {
 public:
  using Load = std::function<cv::Mat(const storage::FrameRecord&)>;

  // `load` runs on background threads (look-ahead ≥ 1), as many at once as
  // the look-ahead allows: it must be safe to call concurrently (load_frame
  // is). Throws std::invalid_argument for a negative look-ahead or an empty
  // load.
  FramePrefetch(std::vector<storage::FrameRecord> frames, Load load, int look_ahead_frames = 1);
  // The frames of the run in `run_dir`, loaded by load_frame (run_selection.h).
  FramePrefetch(const std::filesystem::path& run_dir, std::vector<storage::FrameRecord> frames,
                int look_ahead_frames = 1);
  ~FramePrefetch();

  FramePrefetch(const FramePrefetch&) = delete;
  FramePrefetch& operator=(const FramePrefetch&) = delete;

  // The next frame and its image; nullopt after the last. Rethrows the
  // frame's load error (the prefetch then goes on with the frame after it).
  std::optional<PrefetchedFrame> next();
  // Frames next() has still to hand out (a caller checks its stop request
  // before waiting for one).
  std::size_t remaining() const;

 private:
  struct Loaded {
    cv::Mat image;
    double seconds = 0;
  };

  Loaded load_timed(const storage::FrameRecord& frame) const;
  void start_loads();

  const std::vector<storage::FrameRecord> frames_;
  const Load load_;
  const std::size_t look_ahead_;
  std::size_t next_to_start_ = 0;
  std::size_t next_to_return_ = 0;
  std::deque<std::future<Loaded>> in_flight_;  // frames next_to_return_ … next_to_start_ - 1
};

}  // namespace bosfuse::pipeline
