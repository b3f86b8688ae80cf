// The watched folder against files a test writes: new files become frames,
// half-written ones never do, EXIF times are used where present.

#include "acquisition/cameras/watched_folder_source.h"

#include <gtest/gtest.h>

#include <thread>

#include "acquisition/clock.h"
#include "tests/support/forged_image.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;
using testing::encoded;
using testing::textured_frame;
using testing::write_file;

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

class WatchedFolder : public ::testing::Test {
 protected:
  WatchedFolderSource open_source(double offset_s = 0) {
    WatchedFolderSource source({dir.path(), 150ms, offset_s, 120s});
    source.connect();
    return source;
  }
  testing::TempDir dir;
};

TEST_F(WatchedFolder, NewFilesBecomeFramesInNameOrderAndOldOnesAreLeftAlone) {
  write_file(dir.path() / "old.png", encoded(textured_frame(0), ".png"));
  WatchedFolderSource source = open_source();
  const cv::Mat first = textured_frame(1, CV_16U), second = textured_frame(2);
  write_file(dir.path() / "img_0002.png", encoded(second, ".png"));
  write_file(dir.path() / "img_0001.tif", encoded(first, ".tif"));
  const auto a = source.next(3s);
  const auto b = source.next(3s);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->origin, "img_0001.tif");
  EXPECT_TRUE(same_pixels(a->image, first));  // 16 bits kept
  EXPECT_EQ(b->origin, "img_0002.png");
  EXPECT_TRUE(same_pixels(b->image, second));
  EXPECT_FALSE(source.next(400ms).has_value());  // old.png never comes
}

// Written in pieces with pauses longer than the settle time: the reader must
// wait for the end of the file, never take what is there so far.
TEST_F(WatchedFolder, SlowlyWrittenFileIsNeverReadHalfFinished) {
  WatchedFolderSource source = open_source();
  const cv::Mat image = textured_frame(3, CV_8U, {320, 240});
  for (const std::string ext : {".jpg", ".png"}) {
    const std::vector<std::uint8_t> bytes = encoded(image, ext);
    const auto path = dir.path() / ("slow" + ext);
    std::ofstream out(path, std::ios::binary);
    const std::size_t pieces = 4;
    for (std::size_t i = 0; i < pieces; ++i) {
      const std::size_t from = bytes.size() * i / pieces, to = bytes.size() * (i + 1) / pieces;
      out.write(reinterpret_cast<const char*>(bytes.data() + from), static_cast<std::streamsize>(to - from));
      out.flush();
      if (i + 1 < pieces) {
        EXPECT_FALSE(source.next(400ms).has_value()) << ext << " taken after piece " << i;
      }
    }
    out.close();
    const auto frame = source.next(3s);
    ASSERT_TRUE(frame.has_value()) << ext;
    EXPECT_TRUE(same_pixels(frame->image, cv::imdecode(bytes, cv::IMREAD_UNCHANGED))) << ext;
  }
}

TEST_F(WatchedFolder, TemporaryNamesWaitUntilRenamed) {
  WatchedFolderSource source = open_source();
  write_file(dir.path() / "shot.jpg.part", encoded(textured_frame(4), ".jpg"));
  write_file(dir.path() / ".shot2.png", encoded(textured_frame(5), ".png"));
  EXPECT_FALSE(source.next(400ms).has_value());
  std::filesystem::rename(dir.path() / "shot.jpg.part", dir.path() / "shot.jpg");
  const auto frame = source.next(3s);
  ASSERT_TRUE(frame.has_value());
  EXPECT_EQ(frame->origin, "shot.jpg");
}

TEST_F(WatchedFolder, ExifTimePlusOffsetElseFileTime) {
  WatchedFolderSource source = open_source(-3600.5);  // camera clock one hour and half a second ahead
  const auto staged = dir.path() / "staged";
  std::filesystem::create_directory(staged);
  write_file(staged / "exif.jpg", encoded(textured_frame(6), ".jpg"));
  testing::write_exif(staged / "exif.jpg", {"-DateTimeOriginal=2026:11:23 11:00:00"});
  std::filesystem::rename(staged / "exif.jpg", dir.path() / "a_exif.jpg");
  const auto with_exif = source.next(3s);
  ASSERT_TRUE(with_exif.has_value());
  const std::int64_t camera_ns = 1'795'431'600'000'000'000;  // 2026-11-23T11:00:00 as if UTC
  EXPECT_EQ(with_exif->device_t_ns, camera_ns);
  EXPECT_EQ(with_exif->t_ns, camera_ns - 3'600'500'000'000);

  const auto before_ns = utc_now_ns();
  write_file(dir.path() / "b_plain.png", encoded(textured_frame(7), ".png"));
  const auto plain = source.next(3s);
  ASSERT_TRUE(plain.has_value());
  EXPECT_FALSE(plain->device_t_ns.has_value());
  EXPECT_NEAR(static_cast<double>(plain->t_ns - before_ns), 0.0, 2e9);  // its modification time
}

// A file padded to 1.9 GB is a lost frame at once (it can never become an
// image); half a JPEG is tried again as long as it may still be written, then
// lost with libjpeg's reason. Either way the folder goes on to the next file.
TEST_F(WatchedFolder, APaddedOrTruncatedFileIsALostFrameAndTheFolderGoesOn) {
  WatchedFolderSource source({dir.path(), 100ms, 0, 1s});
  source.connect();
  testing::write_padded(dir.path() / "a_padded.png", encoded(textured_frame(8), ".png"), 1'900'000'000);
  const std::vector<std::uint8_t> jpeg = encoded(textured_frame(9, CV_8U, {320, 240}), ".jpg");
  write_file(dir.path() / "b_half.jpg", std::vector<std::uint8_t>(jpeg.begin(), jpeg.begin() + jpeg.size() / 2));
  const cv::Mat good = textured_frame(10);
  write_file(dir.path() / "c_good.png", encoded(good, ".png"));

  std::vector<std::string> lost;
  std::vector<CapturedFrame> frames;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((lost.size() < 2 || frames.empty()) && std::chrono::steady_clock::now() < deadline) {
    try {
      if (auto frame = source.next(200ms)) frames.push_back(std::move(*frame));
    } catch (const FrameLost& e) {
      lost.push_back(e.what());
    }
  }
  ASSERT_EQ(lost.size(), 2u);
  EXPECT_EQ(lost[0].rfind((dir.path() / "a_padded.png").string() + ": the file is 1900000000 bytes", 0), 0u) << lost[0];
  EXPECT_NE(lost[0].find("; the frame is skipped"), std::string::npos) << lost[0];
  EXPECT_EQ(lost[1].rfind("b_half.jpg never became a complete image (", 0), 0u) << lost[1];
  EXPECT_NE(lost[1].find("libjpeg: Premature end of JPEG file"), std::string::npos) << lost[1];
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].origin, "c_good.png");
  EXPECT_TRUE(same_pixels(frames[0].image, good));
  EXPECT_FALSE(source.next(300ms).has_value()) << "each lost file is lost once";
}

TEST_F(WatchedFolder, MissingFolderIsADeviceError) {
  WatchedFolderSource source({dir.path() / "nowhere", 100ms, 0, 1s});
  EXPECT_THROW(source.connect(), DeviceError);
}

}  // namespace
}  // namespace bosfuse::acquisition
