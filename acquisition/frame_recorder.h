#pragma once
// A FrameRecorder takes frames from one FrameSource on its own thread and
// stores them in the run: each frame as a lossless PNG at the bit depth the
// camera delivered (8 or 16 bit), under frames/<camera>/ in the run folder,
// written under a temporary name and renamed so no half-written image ever
// carries a frame's name, then referenced from the run store with its t_ns.
// Live cameras are read on a fixed schedule (frame k at start + k·interval);
// a watched folder is read as files arrive. The first frames, and frames
// taken while the reference flag file exists, are reference (no-flow)
// frames. A camera that fails is reported, reconnected with backoff and
// recorded as events, like a thermocouple reader.

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <thread>

#include "acquisition/connection_keeper.h"
#include "acquisition/frame_source.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

class FrameRecorder {
 public:
  struct Options {
    std::chrono::nanoseconds interval{0};  // 0: take frames as they come
    int reference_frames = 1;              // the first N frames are references
    std::filesystem::path reference_flag;  // frames are references while this file exists
    ConnectionKeeper::Backoff backoff;
    std::string Validate() const;
  };

  struct Stats {
    std::int64_t frames = 0;
    std::int64_t reference_frames = 0;
    std::int64_t failures = 0;  // frames the camera or the disk lost
    bool connected = false;
    bool finished = false;  // a finite source (a video file) has ended
  };

  // `name` names the camera's folder under frames/ (letters, digits, - and _).
  FrameRecorder(std::unique_ptr<FrameSource> source, std::string name, std::int64_t device_id,
                std::filesystem::path run_dir, storage::RunWriter& writer, Options options);
  ~FrameRecorder();  // stops; never throws
  FrameRecorder(const FrameRecorder&) = delete;
  FrameRecorder& operator=(const FrameRecorder&) = delete;

  void start();
  void stop();
  Stats stats() const;
  const std::string& name() const { return name_; }

 private:
  using SteadyTime = std::chrono::steady_clock::time_point;

  void run();
  bool ensure_connected();
  bool take_one(std::chrono::milliseconds wait);  // false when the source has ended
  void store(const CapturedFrame& frame);
  bool is_reference_now() const;
  void record_event(const std::string& kind, const std::string& message);
  bool wait_until(SteadyTime deadline);

  std::unique_ptr<FrameSource> source_;
  std::string name_;
  std::int64_t device_id_;
  std::filesystem::path run_dir_;
  std::filesystem::path frame_dir_;  // relative to run_dir_
  storage::RunWriter& writer_;
  Options options_;
  ConnectionKeeper connection_;

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  Stats stats_;
  std::thread thread_;
};

}  // namespace bosfuse::acquisition
