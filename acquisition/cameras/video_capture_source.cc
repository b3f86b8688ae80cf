#include "acquisition/cameras/video_capture_source.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "acquisition/clock.h"

namespace bosfuse::acquisition {
namespace {

bool is_camera_index(const std::string& target) {
  return !target.empty() && std::all_of(target.begin(), target.end(), [](unsigned char c) { return std::isdigit(c); });
}

}  // namespace

int bit_depth_of(const cv::Mat& image) { return image.depth() == CV_16U || image.depth() == CV_16S ? 16 : 8; }

VideoCaptureSource::VideoCaptureSource(std::string target) : target_(std::move(target)) {}

std::string VideoCaptureSource::describe() const {
  return is_camera_index(target_) ? "camera " + target_ : "video " + target_;
}

void VideoCaptureSource::connect() {
  is_file_ = std::filesystem::is_regular_file(target_);
  const bool opened = is_camera_index(target_) ? capture_.open(std::stoi(target_)) : capture_.open(target_);
  if (!opened || !capture_.isOpened()) throw DeviceError("cannot open " + describe());
  if (!is_file_) capture_.set(cv::CAP_PROP_BUFFERSIZE, 1);  // where the backend supports it
}

void VideoCaptureSource::disconnect() { capture_.release(); }

std::optional<CapturedFrame> VideoCaptureSource::next(std::chrono::milliseconds) {
  if (!capture_.isOpened()) throw DeviceError(describe() + " is not open");
  CapturedFrame frame;
  frame.t_ns = utc_now_ns();
  if (!capture_.grab() || !capture_.retrieve(frame.image) || frame.image.empty()) {
    if (is_file_) throw EndOfFrames(describe() + " has no more frames");
    throw DeviceError(describe() + " delivered no frame");
  }
  frame.origin = describe() + " frame " + std::to_string(frames_read_++);
  return frame;
}

}  // namespace bosfuse::acquisition
