#pragma once
// RecordedFrameSource replays one camera of a recorded run: its frame files
// in order, each when it is due (its original time since the run's origin,
// divided by the replay speed), with its reference flag and its original
// t_ns kept as the camera's own time. A frame whose file is missing or
// unreadable is skipped with a warning, so a damaged run replays what is
// sound; the source ends (EndOfFrames) after the last frame.

#include <filesystem>
#include <vector>

#include "acquisition/cameras/frame_source.h"
#include "storage/records.h"

namespace bosfuse::acquisition {

struct RecordedFrames {
  std::filesystem::path run_dir;
  std::vector<storage::FrameRecord> frames;  // one camera's, in time order
  std::int64_t origin_ns = 0;                // the recorded run's time zero
  double speed = 1;
};

class RecordedFrameSource : public FrameSource {
 public:
  explicit RecordedFrameSource(RecordedFrames recorded);

  std::string kind() const override { return "replay"; }
  std::string describe() const override;
  void connect() override;
  void disconnect() override {}
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override;

  std::size_t skipped() const { return skipped_; }

 private:
  RecordedFrames recorded_;
  std::chrono::steady_clock::time_point started_;
  std::size_t next_ = 0;
  std::size_t skipped_ = 0;
  bool opened_ = false;
};

// Loads one camera's frames of the run in `run_dir` (by the camera's device name).
RecordedFrames load_recorded_frames(const std::filesystem::path& run_dir, const std::string& camera, double speed);

}  // namespace bosfuse::acquisition
