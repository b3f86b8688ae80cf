#include "pipeline/image_sequence.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <fstream>

#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"
#include "tests/support/file_bytes.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

void set_mtime(const fs::path& path, std::int64_t seconds, long nanoseconds) {
  const timespec times[2] = {{seconds, nanoseconds}, {seconds, nanoseconds}};
  ASSERT_EQ(utimensat(AT_FDCWD, path.c_str(), times, 0), 0) << path;
}

std::int64_t utc_ns(int y, int mo, int d, int h, int mi, int s) {
  const auto t = std::chrono::sys_days(std::chrono::year(y) / mo / d) + std::chrono::hours(h) +
                 std::chrono::minutes(mi) + std::chrono::seconds(s);
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

TEST(NaturalOrder, NumbersCompareByValue) {
  std::vector<std::string> names = {"frame_10.tif", "frame_2.tif", "frame_1.tif", "frame_100.tif", "frame_9.tif"};
  std::sort(names.begin(), names.end(), natural_less);
  EXPECT_EQ(names,
            (std::vector<std::string>{"frame_1.tif", "frame_2.tif", "frame_9.tif", "frame_10.tif", "frame_100.tif"}));
}

TEST(NaturalOrder, SeveralNumbersTextAndPrefixes) {
  EXPECT_TRUE(natural_less("run2/frame_10", "run10/frame_2"));
  EXPECT_TRUE(natural_less("a2b3", "a2b10"));
  EXPECT_TRUE(natural_less("frame", "frame_1"));
  EXPECT_FALSE(natural_less("frame_1", "frame"));
  EXPECT_TRUE(natural_less("a_5", "b_1")) << "text before the number decides first";
  EXPECT_FALSE(natural_less("frame_2", "frame_2"));
  // Longer than any integer type: compared as digit strings, no overflow.
  EXPECT_TRUE(natural_less("f_99999999999999999999999", "f_100000000000000000000000"));
}

TEST(NaturalOrder, LeadingZerosCompareByValueThenByBytes) {
  EXPECT_TRUE(natural_less("frame_002", "frame_10"));
  EXPECT_TRUE(natural_less("frame_0010", "frame_11"));
  // Equal values: a strict, total order all the same.
  EXPECT_NE(natural_less("frame_02", "frame_2"), natural_less("frame_2", "frame_02"));
  EXPECT_TRUE(natural_less("frame_0", "frame_00") || natural_less("frame_00", "frame_0"));
}

class Sequence : public ::testing::Test {
 protected:
  fs::path touch(const std::string& name) {
    const auto path = dir.path() / name;
    fs::create_directories(path.parent_path());
    const std::string ext = path.extension().string();
    const bool image = ext == ".png" || ext == ".tif" || ext == ".jpg";
    testing::write_file(path, testing::encoded(testing::textured_frame(1), image ? ext : ".png"));
    return path;
  }
  std::vector<std::string> names(const std::vector<std::string>& paths) {
    std::vector<std::string> out;
    for (const auto& p : paths) out.push_back(fs::path(p).filename().string());
    return out;
  }
  testing::TempDir dir;
};

TEST_F(Sequence, AGlobIsExpandedAndSortedNaturally) {
  for (const char* name : {"f_10.png", "f_2.png", "f_1.png", "notes.txt"}) touch(name);
  fs::create_directories(dir.path() / "f_3.png");  // a folder the pattern matches is no frame
  const auto sequence = list_image_sequence((dir.path() / "f_*.png").string(), {});
  EXPECT_EQ(names(sequence.frames), (std::vector<std::string>{"f_1.png", "f_2.png", "f_10.png"}));
  EXPECT_EQ(sequence.frames.front(), (dir.path() / "f_1.png").string()) << "paths as the pattern gave them";
  EXPECT_TRUE(sequence.left_out.empty());
}

TEST_F(Sequence, AFolderGivesItsImagesAndLeavesOutTheReferenceAndTheMask) {
  for (const char* name : {"ref.png", "mask.png", "b_10.tif", "b_9.tif", "readme.txt", ".hidden.png"}) touch(name);
  touch("sub/b_1.tif");
  const auto sequence =
      list_image_sequence(dir.path().string(), {(dir.path() / "ref.png").string(), (dir.path() / "mask.png").string()});
  EXPECT_EQ(names(sequence.frames), (std::vector<std::string>{"b_9.tif", "b_10.tif"}));
  EXPECT_EQ(names(sequence.left_out), (std::vector<std::string>{"mask.png", "ref.png"}));
}

TEST_F(Sequence, NothingToEvaluateIsAnErrorNamingThePattern) {
  touch("ref.png");
  const std::string none = (dir.path() / "*.tif").string();
  try {
    list_image_sequence(none, {});
    FAIL() << "no match";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(none + "': no file matches"), std::string::npos) << e.what();
  }
  try {
    list_image_sequence((dir.path() / "*.png").string(), {(dir.path() / "ref.png").string()});
    FAIL() << "only the reference";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("besides the reference"), std::string::npos) << e.what();
  }
}

TEST_F(Sequence, TheTimeIsTheExifCaptureTimeWhenThereIsOne) {
  const auto jpeg = touch("a.jpg");
  testing::write_exif(jpeg, {"-DateTimeOriginal=2026:11:23 10:15:30", "-SubSecTimeOriginal=250"});
  set_mtime(jpeg, 1'000'000'000, 0);  // an mtime that must not be taken
  const FrameTime t = frame_time(jpeg, testing::file_byte_vector(jpeg));
  ASSERT_TRUE(t.t_ns.has_value());
  EXPECT_EQ(*t.t_ns, utc_ns(2026, 11, 23, 10, 15, 30) + 250'000'000);
  EXPECT_EQ(t.source, TimeSource::kExif);
  EXPECT_EQ(to_string(t.source), "exif");

  const auto zoned = touch("b.tif");
  testing::write_exif(zoned, {"-DateTimeOriginal=2026:11:23 11:15:30", "-OffsetTimeOriginal=+01:00"});
  const FrameTime z = frame_time(zoned, testing::file_byte_vector(zoned));
  EXPECT_EQ(z.t_ns, utc_ns(2026, 11, 23, 10, 15, 30));
  EXPECT_EQ(z.source, TimeSource::kExifWithOffset);
}

TEST_F(Sequence, WithoutExifTheTimeIsTheModificationTime) {
  const auto png = touch("c.png");
  set_mtime(png, 1'764'000'000, 125'000'000);
  const FrameTime t = frame_time(png, testing::file_byte_vector(png));
  EXPECT_EQ(t.t_ns, 1'764'000'000'125'000'000);
  EXPECT_EQ(t.source, TimeSource::kFileModification);
  EXPECT_EQ(to_string(t.source), "mtime");

  const FrameTime gone = frame_time(dir.path() / "gone.png", {});
  EXPECT_FALSE(gone.t_ns.has_value());
  EXPECT_EQ(to_string(gone.source), "none");
}

}  // namespace
}  // namespace bosfuse::pipeline
