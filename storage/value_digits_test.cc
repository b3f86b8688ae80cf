#include "storage/value_digits.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::storage {
namespace {

TEST(ValueDigits, DecimalsFollowTheResolution) {
  EXPECT_EQ(resolution_decimals(0.1), 1);
  EXPECT_EQ(resolution_decimals(0.01), 2);
  EXPECT_EQ(resolution_decimals(1370.0 / 65535), 2);
  EXPECT_EQ(resolution_decimals(0.25), 1);
  EXPECT_EQ(resolution_decimals(1.0), 0);
  EXPECT_EQ(resolution_decimals(5.0), 0);
  EXPECT_EQ(resolution_decimals(std::nullopt), std::nullopt);
  EXPECT_EQ(resolution_decimals(0.0), std::nullopt);
}

TEST(ValueDigits, AQuantisedValuePrintsAtItsDigits) {
  EXPECT_EQ(format_channel_value(234 * 0.1, 0.1), "23.4");
  EXPECT_EQ(format_channel_value(2345 * 0.01, 0.01), "23.45");
  EXPECT_EQ(format_channel_value(-0.04, 0.1), "0.0");
  EXPECT_EQ(format_channel_value(812.0, 1.0), "812");
}

TEST(ValueDigits, AnUnknownResolutionPrintsSixSignificantDigits) {
  EXPECT_EQ(format_channel_value(23.100000000000001, std::nullopt), "23.1");
  EXPECT_EQ(format_channel_value(48.27312345, std::nullopt), "48.2731");
  EXPECT_EQ(format_channel_value(std::nan(""), 0.1), "");
}

}  // namespace
}  // namespace bosfuse::storage
