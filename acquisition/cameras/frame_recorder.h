#pragma once
// A FrameRecorder takes frames from one FrameSource on its own thread and
// stores them in the run: each frame as a lossless PNG at the bit depth the
// camera delivered (8 or 16 bit; stored uncompressed, acquisition/cameras/frame_png.h),
// under frames/<camera>/ in the run folder,
// written under a temporary name and renamed so no half-written image ever
// carries a frame's name, then referenced from the run store with its t_ns.
// Live cameras are read on a fixed schedule (frame k at start + k·interval);
// a watched folder is read as files arrive. The first frames, and frames
// taken while the reference flag file exists, are reference (no-flow)
// frames. A camera that fails is reported, reconnected with backoff and
// recorded as events, like a thermocouple reader (it is a DeviceWorker).

#include <filesystem>
#include <memory>
#include <mutex>

#include "acquisition/connection_keeper.h"
#include "acquisition/device_worker.h"
#include "acquisition/cameras/frame_source.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

// What a FrameRecorder is set up with.
struct FrameRecorderOptions {
  std::chrono::nanoseconds interval{0};  // 0: take frames as they come
  int reference_frames = 1;              // the first N frames are references
  std::filesystem::path reference_flag;  // frames are references while this file exists
  ConnectionKeeper::Backoff backoff;
  // Frames in a row that must arrive before an outage is declared over,
  // as for a thermocouple reader (DevicePollerOptions::recovery_polls).
  int recovery_frames = 3;
  std::string Validate() const;
};

class FrameRecorder : public DeviceWorker {
 public:
  struct Stats {
    std::int64_t frames = 0;
    std::int64_t reference_frames = 0;
    std::int64_t failures = 0;  // frames the camera or the disk lost
    bool connected = false;
    bool finished = false;  // a finite source (a video file) has ended
  };

  // `name` names the camera's folder under frames/ (letters, digits, - and _).
  // Own it in a std::shared_ptr (std::make_shared) before start().
  FrameRecorder(std::unique_ptr<FrameSource> source, std::string name, std::int64_t device_id,
                std::filesystem::path run_dir, storage::RunWriter& writer, FrameRecorderOptions options);

  Stats stats() const;

 private:
  void loop() override;
  void record_frames();
  void disconnect_device() noexcept override;
  bool ensure_connected();
  bool take_one(std::chrono::milliseconds wait);  // false when the source has ended
  void store(const CapturedFrame& frame);
  void record_notes();  // the source's notes as events
  bool is_reference_now() const;

  std::unique_ptr<FrameSource> source_;
  std::filesystem::path run_dir_;
  std::filesystem::path frame_dir_;  // relative to run_dir_
  FrameRecorderOptions options_;
  ConnectionKeeper connection_;  // used on the worker thread only

  mutable std::mutex stats_mutex_;
  Stats stats_;
};

}  // namespace bosfuse::acquisition
