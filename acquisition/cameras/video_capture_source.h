#pragma once
// VideoCaptureSource reads frames with OpenCV's VideoCapture: a V4L2 camera
// by index ("0"), a video file, or a stream URL. Each frame is stamped with
// the host UTC clock when it is grabbed. A camera keeps one frame buffered so
// a frame taken at the recorder's interval is fresh, not one queued long
// ago; a video file ends with EndOfFrames.

#include <opencv2/videoio.hpp>

#include "acquisition/cameras/frame_source.h"

namespace bosfuse::acquisition {

class VideoCaptureSource : public FrameSource {
 public:
  explicit VideoCaptureSource(std::string target);  // index, file or URL

  std::string kind() const override { return "video"; }
  std::string describe() const override;
  void connect() override;
  void disconnect() override;
  std::optional<CapturedFrame> next(std::chrono::milliseconds wait) override;

 private:
  std::string target_;
  bool is_file_ = false;
  std::int64_t frames_read_ = 0;
  cv::VideoCapture capture_;
};

}  // namespace bosfuse::acquisition
