#pragma once
// A FrameSource is one camera that yields timestamped images: an OpenCV
// VideoCapture (V4L2 device, video file or stream URL), a folder a tethered
// DSLR writes into, or a virtual camera. Each frame carries t_ns on the host
// UTC clock, like every thermocouple sample, and the camera's own time when
// it has one. The FrameRecorder drives a source on its own thread and stores
// what it yields; a source only knows how to get the next image. Sources are
// used from one thread at a time.

#include <chrono>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/device_reading.h"

namespace bosfuse::acquisition {

struct CapturedFrame {
  cv::Mat image;                            // as the camera delivered it: 8- or 16-bit, grey or colour
  std::int64_t t_ns = 0;                    // host UTC clock
  std::optional<std::int64_t> device_t_ns;  // the camera's clock, when known
  std::string origin;                       // e.g. the file it came from
  std::optional<bool> is_reference;         // set when the source knows (a replay)
  // When the host received it, where t_ns is the camera's time mapped to
  // the host clock (a GenICam camera); unset where t_ns is the arrival.
  std::optional<std::int64_t> arrival_ns;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  virtual std::string kind() const = 0;      // "video", "folder", "virtual": stored as the device's profile
  virtual std::string describe() const = 0;  // "camera 0", "folder /data/dslr"
  // The same verbs as a thermocouple source (thermocouple_source.h).
  virtual void connect() = 0;     // throws DeviceError
  virtual void disconnect() = 0;  // never throws
  // The next frame, waiting at most `wait`; nullopt when none came in time.
  // Throws DeviceError when the camera is gone, EndOfFrames when a finite
  // source (a video file) has no more, and FrameLost for a frame it lost.
  virtual std::optional<CapturedFrame> next(std::chrono::milliseconds wait) = 0;

  // What the source noticed beside its frames since it was last asked: a
  // camera-clock mapping, frames the camera dropped without a buffer to
  // show for them. The recorder stores each as an event after next().
  struct Note {
    std::string kind;  // an event kind: "clock", "error", ...
    std::string message;
    std::int64_t lost_frames = 0;  // counted with the recorder's failures
  };
  virtual std::vector<Note> take_notes() { return {}; }
};

class EndOfFrames : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown by next() for a frame the camera took but the source cannot
// deliver (a watched folder's file refused as too large, truncated or
// damaged; the message names it and says why). The recorder counts it as a
// lost frame and records why; the camera stays connected and goes on.
class FrameLost : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Significant bits of an image's pixel type: 8 or 16.
int bit_depth_of(const cv::Mat& image);

}  // namespace bosfuse::acquisition
