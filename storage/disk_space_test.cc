// The disk watch: a disk filling up is said once, before it is full, with
// the time left; once again when it has room; a run folder not made yet is
// measured on the folder that will hold it.

#include "storage/disk_space.h"

#include <gtest/gtest.h>

#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

using namespace std::chrono_literals;
constexpr std::uint64_t kMB = 1 << 20;

TEST(DiskFillWatch, ADiskFillingUpIsSaidOnceWithTheTimeLeftAndOnceWhenItHasRoom) {
  DiskFillWatch watch({10 * kMB, 3600s, 60s});
  const auto t0 = std::chrono::steady_clock::time_point{};
  // 10 GB free, 1 MB/s: full in 10240 s, more than an hour.
  std::uint64_t free = 10'240 * kMB;
  for (int s = 0; s <= 60; s += 5) {
    EXPECT_FALSE(watch.add(t0 + std::chrono::seconds(s), free - s * kMB)) << "at " << s << " s";
  }
  // Then 5 MB/s: the window's rate passes the hour's mark within a minute.
  free -= 60 * kMB;
  std::optional<DiskFillWatch::Change> began;
  int said = 0;
  for (int s = 65; s <= 180; s += 5) {
    free -= 25 * kMB;
    if (auto change = watch.add(t0 + std::chrono::seconds(s), free)) {
      ++said;
      began = change;
    }
  }
  ASSERT_EQ(said, 1) << "said once, not at every sample";
  EXPECT_TRUE(began->short_of_space);
  EXPECT_NE(began->message.find("MB/s: full in about"), std::string::npos) << began->message;
  ASSERT_TRUE(watch.time_to_full());
  EXPECT_NEAR(static_cast<double>(watch.time_to_full()->count()), static_cast<double>(free) / (5.0 * kMB), 60);
  // The filling stops and a file is deleted.
  const auto ended = watch.add(t0 + 250s, free + 5000 * kMB);
  ASSERT_TRUE(ended);
  EXPECT_FALSE(ended->short_of_space);
  EXPECT_NE(ended->message.find("room again"), std::string::npos) << ended->message;
}

TEST(DiskFillWatch, LessThanTheLeastFreeSpaceIsSaidEvenWhenNotFilling) {
  DiskFillWatch watch({100 * kMB, 3600s, 60s});
  const auto t0 = std::chrono::steady_clock::time_point{};
  const auto change = watch.add(t0, 40 * kMB);
  ASSERT_TRUE(change);
  EXPECT_TRUE(change->short_of_space);
  EXPECT_NE(change->message.find("40 MB free"), std::string::npos) << change->message;
  EXPECT_NE(change->message.find("min_free_mb"), std::string::npos) << change->message;
  EXPECT_FALSE(watch.add(t0 + 5s, 40 * kMB));
  EXPECT_FALSE(watch.add(t0 + 10s, 150 * kMB)) << "within twice the margin it is still short";
  EXPECT_TRUE(watch.add(t0 + 15s, 250 * kMB));
}

TEST(DiskFillWatch, WithNoLeastFreeSpaceOnlyTheTimeLeftCounts) {
  DiskFillWatch watch({0, 3600s, 60s});
  const auto t0 = std::chrono::steady_clock::time_point{};
  EXPECT_FALSE(watch.add(t0, 1 * kMB));
  EXPECT_FALSE(watch.add(t0 + 5s, 1 * kMB)) << "a small disk that is not filling is no warning";
  const auto change = watch.add(t0 + 10s, kMB / 2);
  ASSERT_TRUE(change);
  EXPECT_NE(change->message.find("full in about 10 s"), std::string::npos) << change->message;
}

TEST(FreeBytes, AFolderNotMadeYetIsMeasuredOnTheOneThatWillHoldIt) {
  testing::TempDir dir;
  const std::uint64_t here = free_bytes(dir.path());
  const std::uint64_t there = free_bytes(dir / "not/made/yet");
  EXPECT_GT(here, 0u);
  // The same file system; others may write to it meanwhile.
  EXPECT_NEAR(static_cast<double>(there), static_cast<double>(here), 64.0 * kMB);
}

TEST(BytesText, CountsInPowersOf1024) {
  EXPECT_EQ(bytes_text(512 * 1024), "512 KB");
  EXPECT_EQ(bytes_text(100 * kMB), "100 MB");
  EXPECT_EQ(bytes_text(3 * 1024 * kMB / 2), "1.5 GB");
}

}  // namespace
}  // namespace bosfuse::storage
