// VideoCapture on a short video file the test writes with OpenCV's own
// MJPEG encoder.

#include "acquisition/cameras/video_capture_source.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "acquisition/clock.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::acquisition {
namespace {

TEST(VideoCaptureSource, ReadsEveryFrameOfAFileThenEnds) {
  testing::TempDir dir;
  const auto path = dir.path() / "clip.avi";
  const int frame_count = 6;
  {
    cv::VideoWriter writer(path.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, {96, 64}, true);
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < frame_count; ++i) {
      cv::Mat frame(64, 96, CV_8UC3, cv::Scalar::all(20 + 30 * i));  // brightness identifies the frame
      writer.write(frame);
    }
  }
  VideoCaptureSource source(path.string());
  source.connect();
  std::int64_t previous_ns = 0;
  for (int i = 0; i < frame_count; ++i) {
    const auto frame = source.next(std::chrono::milliseconds(100));
    ASSERT_TRUE(frame.has_value());
    EXPECT_EQ(frame->image.size(), cv::Size(96, 64));
    EXPECT_NEAR(cv::mean(frame->image)[0], 20 + 30 * i, 3.0) << "frame " << i;
    EXPECT_GT(frame->t_ns, previous_ns);
    previous_ns = frame->t_ns;
  }
  EXPECT_THROW(source.next(std::chrono::milliseconds(100)), EndOfFrames);
}

TEST(VideoCaptureSource, MissingFileIsADeviceError) {
  VideoCaptureSource source("/nonexistent/clip.avi");
  EXPECT_THROW(source.connect(), DeviceError);
  EXPECT_EQ(source.describe(), "video /nonexistent/clip.avi");
  EXPECT_EQ(VideoCaptureSource("2").describe(), "camera 2");
}

}  // namespace
}  // namespace bosfuse::acquisition
