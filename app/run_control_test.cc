#include "app/run_control.h"

#include <gtest/gtest.h>

namespace bosfuse::app {
namespace {

using namespace std::chrono_literals;

TEST(ParseDuration, ReadsUnits) {
  EXPECT_EQ(parse_duration("90"), 90s);
  EXPECT_EQ(parse_duration("30s"), 30s);
  EXPECT_EQ(parse_duration("10m"), 10min);
  EXPECT_EQ(parse_duration("1.5h"), 90min);
  EXPECT_EQ(parse_duration("250ms"), 250ms);
}

TEST(ParseDuration, RejectsNonsense) {
  for (const char* bad : {"", "ten", "10x", "-5s", "0", "nan", "5 s"}) {
    EXPECT_THROW(parse_duration(bad), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace bosfuse::app
