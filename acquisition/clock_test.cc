#include "acquisition/clock.h"

#include <gtest/gtest.h>

namespace bosfuse::acquisition {
namespace {

TEST(Clock, FormatsIso8601Utc) {
  const std::int64_t t = 1'779'527'628'289'123'456;  // 2026-05-23T09:13:48.289123456Z
  EXPECT_EQ(format_iso8601_utc(t, 9), "2026-05-23T09:13:48.289123456Z");
  EXPECT_EQ(format_iso8601_utc(t, 3), "2026-05-23T09:13:48.289Z");
  EXPECT_EQ(format_iso8601_utc(t, 0), "2026-05-23T09:13:48Z");
  EXPECT_EQ(format_compact_utc(t), "20260523T091348Z");
}

TEST(Clock, TimesBeforeTheEpochKeepAPositiveFraction) {
  EXPECT_EQ(format_iso8601_utc(-1, 9), "1969-12-31T23:59:59.999999999Z");
}

TEST(Clock, NowIsCloseToTheSystemClock) {
  const auto now = utc_now_ns();
  EXPECT_GT(now, 1'700'000'000'000'000'000);  // after 2023
  EXPECT_LT(now, 4'102'444'800'000'000'000);  // before 2100
}

}  // namespace
}  // namespace bosfuse::acquisition
