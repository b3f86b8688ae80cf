#include "app/time_argument.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace bosfuse::app {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
// 2026-12-01T18:11:29Z
constexpr std::int64_t kDecemberFirst = 1'796'148'689LL * kSecond;

TEST(TimeArgument, ReadsAUtcTimeWithItsFractionAndZone) {
  EXPECT_EQ(parse_time_argument("2026-12-01T18:11:29Z").utc_ns, kDecemberFirst);
  EXPECT_EQ(parse_time_argument("2026-12-01T18:11:29.5Z").utc_ns, kDecemberFirst + kSecond / 2);
  EXPECT_EQ(parse_time_argument("2026-12-01T18:11:29.000000001Z").utc_ns, kDecemberFirst + 1);
  EXPECT_EQ(parse_time_argument("2026-12-01T19:11:29+01:00").utc_ns, kDecemberFirst);
  EXPECT_EQ(parse_time_argument("2026-12-01T17:41:29-00:30").utc_ns, kDecemberFirst);
  EXPECT_FALSE(parse_time_argument("2026-12-01T18:11:29Z").from_first_sample);
}

TEST(TimeArgument, ReadsATimeFromTheFirstSampleWithItsUnit) {
  const TimeArgument t = parse_time_argument("+12.5s");
  EXPECT_TRUE(t.from_first_sample);
  EXPECT_DOUBLE_EQ(t.offset_s, 12.5);
  EXPECT_DOUBLE_EQ(parse_time_argument("+250ms").offset_s, 0.25);
  EXPECT_DOUBLE_EQ(parse_time_argument("+3min").offset_s, 180);
  EXPECT_DOUBLE_EQ(parse_time_argument("+1.5h").offset_s, 5400);
  EXPECT_DOUBLE_EQ(parse_time_argument("+0s").offset_s, 0);
}

TEST(TimeArgument, RefusesWhatItCannotReadSayingTheForms) {
  for (const char* text : {"", "+12.5", "+12.5 parsecs", "+s", "2026-12-01 18:11:29Z", "2026-12-01T18:11:29",
                           "2026-02-30T00:00:00Z", "2026-13-01T00:00:00Z", "2026-12-01T24:00:00Z",
                           "2026-12-01T18:11:29.Zulu", "2026-12-01T18:11:29+0100", "yesterday"}) {
    SCOPED_TRACE(text);
    try {
      parse_time_argument(text);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("e.g. 2026-12-01T18:11:29.5Z"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("+12.5s"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace bosfuse::app
