#include "fusion/evaluation.h"

#include <gtest/gtest.h>

#include <climits>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

const cv::Size kImage(128, 96);

TEST(EffectiveRoi, AnEmptyRoiIsTheWholeImage) { EXPECT_EQ(effective_roi({}, kImage), cv::Rect(0, 0, 128, 96)); }

TEST(EffectiveRoi, IsClippedToTheImage) {
  EXPECT_EQ(effective_roi({-10, 20, 50, 500}, kImage), cv::Rect(0, 20, 40, 76));
}

// width * height = 2^32 wrapped to 0 in cv::Rect::area, which read as "no
// ROI" and evaluated the whole image instead of the part from x = 100.
TEST(EffectiveRoi, AHugeRoiIsClippedNotMistakenForNone) {
  EXPECT_EQ(effective_roi({100, 0, 65536, 65536}, kImage), cv::Rect(100, 0, 28, 96));
  EXPECT_EQ(effective_roi({0, 0, INT_MAX, INT_MAX}, kImage), cv::Rect(0, 0, 128, 96));
}

TEST(EffectiveRoi, OutsideTheImageIsAnErrorThatSaysSo) {
  try {
    effective_roi({INT_MAX, 0, 10, 10}, kImage);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "region of interest 2147483647,0,10,10 lies outside the 128x96 image");
  }
  EXPECT_THROW(effective_roi({INT_MAX, INT_MAX, INT_MAX, INT_MAX}, kImage), std::invalid_argument);
  EXPECT_THROW(effective_roi({INT_MIN, INT_MIN, INT_MAX, INT_MAX}, kImage), std::invalid_argument);
  EXPECT_THROW(effective_roi({10, 10, -5, 20}, kImage), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fusion
