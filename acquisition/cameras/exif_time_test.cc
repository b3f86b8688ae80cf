// EXIF capture times as exiftool writes them into JPEG and TIFF files.

#include "acquisition/cameras/exif_time.h"

#include <gtest/gtest.h>

#include "acquisition/clock.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"
#include "tests/support/file_bytes.h"

namespace bosfuse::acquisition {
namespace {

using testing::encoded;
using testing::textured_frame;

std::int64_t utc_ns(int y, int mo, int d, int h, int mi, int s) {
  const auto t = std::chrono::sys_days(std::chrono::year(y) / mo / d) + std::chrono::hours(h) +
                 std::chrono::minutes(mi) + std::chrono::seconds(s);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

class ExifTime : public ::testing::Test {
 protected:
  std::filesystem::path image(const std::string& name, const std::vector<std::string>& tags) {
    const auto path = dir.path() / name;
    testing::write_file(path, encoded(textured_frame(1), path.extension().string()));
    if (!tags.empty()) testing::write_exif(path, tags);
    return path;
  }
  testing::TempDir dir;
};

TEST_F(ExifTime, JpegCaptureTimeWithSubseconds) {
  const auto t = exif_capture_time(
      testing::file_byte_vector(image("a.jpg", {"-DateTimeOriginal=2026:11:23 10:15:30", "-SubSecTimeOriginal=250"})));
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->t_ns, utc_ns(2026, 11, 23, 10, 15, 30) + 250'000'000);
  EXPECT_FALSE(t->had_zone_offset);
}

TEST_F(ExifTime, ZoneOffsetIsApplied) {
  const auto t = exif_capture_time(
      testing::file_byte_vector(image("b.jpg", {"-DateTimeOriginal=2026:11:23 11:15:30", "-OffsetTimeOriginal=+01:00"})));
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->t_ns, utc_ns(2026, 11, 23, 10, 15, 30));
  EXPECT_TRUE(t->had_zone_offset);
}

// Found by fuzzing: a year far from 1970 overflowed int64 nanoseconds. A
// date no camera could have taken is no capture time (the file time is used).
TEST_F(ExifTime, AnImplausibleYearIsNoCaptureTime) {
  EXPECT_FALSE(exif_capture_time(testing::file_byte_vector(image("far.jpg", {"-DateTimeOriginal=7381:01:02 03:04:05"}))));
  EXPECT_FALSE(exif_capture_time(testing::file_byte_vector(image("old.jpg", {"-DateTimeOriginal=1066:10:14 09:00:00"}))));
  EXPECT_TRUE(exif_capture_time(testing::file_byte_vector(image("ok.jpg", {"-DateTimeOriginal=2099:12:31 23:59:59"}))));
}

TEST_F(ExifTime, TiffCaptureTime) {
  const auto t = exif_capture_time(testing::file_byte_vector(image("c.tif", {"-DateTimeOriginal=2025:01:02 03:04:05"})));
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->t_ns, utc_ns(2025, 1, 2, 3, 4, 5));
}

TEST_F(ExifTime, FilesWithoutOrWithBrokenExifHaveNone) {
  EXPECT_FALSE(exif_capture_time(testing::file_byte_vector(image("d.jpg", {}))).has_value());
  EXPECT_FALSE(exif_capture_time(testing::file_byte_vector(image("e.png", {}))).has_value());
  auto bytes = testing::file_byte_vector(image("f.jpg", {"-DateTimeOriginal=2026:11:23 10:15:30"}));
  for (std::size_t cut = 0; cut < 400 && cut < bytes.size(); cut += 7) {  // truncated anywhere: no crash
    (void)exif_capture_time(std::span(bytes).first(cut));
  }
  EXPECT_FALSE(exif_capture_time({}).has_value());
}

}  // namespace
}  // namespace bosfuse::acquisition
