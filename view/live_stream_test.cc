#include "view/live_stream.h"

#include <gtest/gtest.h>

namespace bosfuse::view {
namespace {

TEST(TailCursor, RoundTripsThroughItsText) {
  const TailCursor cursor{1200, 3, 17};
  EXPECT_EQ(format_cursor(cursor), "1200-3-17");
  EXPECT_EQ(parse_cursor("1200-3-17"), cursor);
}

TEST(TailCursor, RefusesAnythingElse) {
  for (const char* text : {"", "1-2", "1-2-3-4", "a-b-c", "-1-2-3", "1--2-3", "1-2-3 ", "99999999999999999999-0-0"}) {
    EXPECT_FALSE(parse_cursor(text)) << text;
  }
}

}  // namespace
}  // namespace bosfuse::view
