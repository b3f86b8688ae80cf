#include "fusion/field_warp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace bosfuse::fusion {
namespace {

// A smooth image whose value at any real position is known exactly.
double smooth(double x, double y) { return 0.5 + 0.2 * std::sin(0.3 * x + 0.1) * std::cos(0.25 * y - 0.2); }

cv::Mat smooth_image(int size) {
  cv::Mat image(size, size, CV_32F);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) image.at<float>(y, x) = static_cast<float>(smooth(x, y));
  }
  return image;
}

GridField uniform_field(double u, double v) {
  return {{0, 0, 8, 4, 4}, cv::Mat(4, 4, CV_64F, cv::Scalar(u)), cv::Mat(4, 4, CV_64F, cv::Scalar(v))};
}

// A B-spline samples the image's coefficients: at whole-pixel shifts it
// gives the image back, and between pixels the smooth image's values.
TEST(FieldWarp, BSplinesInterpolateThroughTheirCoefficients) {
  const cv::Mat image = smooth_image(64);
  for (const auto interpolator : {Interpolator::kBSpline3, Interpolator::kBSpline5}) {
    cv::Mat coefficients;
    bspline_coefficients(image, interpolator, coefficients);
    const cv::Mat same = warp_region(coefficients, uniform_field(0, 0), cv::Rect(0, 0, 64, 64), interpolator);
    EXPECT_LT(cv::norm(same, image, cv::NORM_INF), 1e-5);
    const cv::Mat warped = warp_region(coefficients, uniform_field(0.37, -1.21), cv::Rect(10, 12, 30, 20), interpolator);
    for (int y = 0; y < 20; y += 3) {
      for (int x = 0; x < 30; x += 3) EXPECT_NEAR(warped.at<float>(y, x), smooth(10 + x + 0.37, 12 + y - 1.21), 2e-3);
    }
  }
}

TEST(FieldWarp, ResamplesAtTheShiftedPositions) {
  const cv::Mat image = smooth_image(64);
  for (const auto interpolator : {Interpolator::kCubic, Interpolator::kLanczos3, Interpolator::kLanczos4}) {
    const cv::Mat warped = warp_region(image, uniform_field(0.37, -1.21), cv::Rect(10, 12, 30, 20), interpolator);
    ASSERT_EQ(warped.size(), cv::Size(30, 20));
    for (int y = 0; y < 20; y += 3) {
      for (int x = 0; x < 30; x += 3) EXPECT_NEAR(warped.at<float>(y, x), smooth(10 + x + 0.37, 12 + y - 1.21), 2e-3);
    }
  }
}

TEST(FieldWarp, IntegerShiftsAndAnEmptyFieldCopyPixels) {
  const cv::Mat image = smooth_image(32);
  const cv::Mat shifted = warp_region(image, uniform_field(2, 1), cv::Rect(4, 4, 8, 8), Interpolator::kLanczos3);
  EXPECT_NEAR(shifted.at<float>(0, 0), image.at<float>(5, 6), 1e-6);
  const cv::Mat copy = warp_region(image, GridField{}, cv::Rect(-2, -2, 6, 6), Interpolator::kCubic);
  EXPECT_EQ(copy.at<float>(0, 0), image.at<float>(0, 0)) << "outside the image the border is replicated";
  EXPECT_EQ(copy.at<float>(5, 5), image.at<float>(3, 3));
}

// Into a buffer that held something else, a view into a larger one, and
// past every edge of the image (the plain copy's replicated border): the
// same pixels as a fresh warp.
TEST(FieldWarp, WarpingIntoAReusedBufferEqualsAFreshWarp) {
  const cv::Mat image = smooth_image(48);
  cv::Mat storage(60, 70, CV_32F, cv::Scalar(-7.0f));
  for (const GridField& field : {uniform_field(0.37, -1.21), GridField{}}) {
    for (const cv::Rect region : {cv::Rect(-3, -2, 54, 52), cv::Rect(5, 6, 20, 10)}) {
      cv::Mat out = storage(cv::Rect({0, 0}, region.size()));
      warp_region(image, field, region, Interpolator::kLanczos3, out);
      ASSERT_EQ(out.data, storage.data) << "the buffer is reused, not replaced";
      const cv::Mat fresh = warp_region(image, field, region, Interpolator::kLanczos3);
      ASSERT_EQ(cv::norm(out, fresh, cv::NORM_INF), 0.0) << region;
    }
  }
}

TEST(FieldWarp, InterpolatesTheFieldBilinearlyBetweenNodes) {
  GridField field{{3.5, 3.5, 8, 2, 2}, (cv::Mat_<double>(2, 2) << 0, 1, 2, 3), cv::Mat::zeros(2, 2, CV_64F)};
  EXPECT_NEAR(interpolate_field(field, 7.5, 3.5).x, 0.5, 1e-12);
  EXPECT_NEAR(interpolate_field(field, 7.5, 7.5).x, 1.5, 1e-12);
  EXPECT_NEAR(interpolate_field(field, -50, -50).x, 0.0, 1e-12) << "held constant outside the grid";
}

// Beyond the outermost nodes the warp continues the field's outermost piece
// for two node steps, then holds it: a window on the outermost node reaches
// past it, and a held field there biased its vector by the field's gradient.
TEST(FieldWarp, ContinuesTheFieldLinearlyForTwoNodeStepsPastTheGrid) {
  const cv::Mat image = smooth_image(64);
  // u = 0.1 (x − 25), v = 0.05 (y − 25) at nodes x = 25, 30, 35 and y = 25, 30.
  GridField field{{25, 25, 5, 2, 3}, (cv::Mat_<double>(2, 3) << 0, 0.5, 1, 0, 0.5, 1),
                  (cv::Mat_<double>(2, 3) << 0, 0, 0, 0.25, 0.25, 0.25)};
  const cv::Mat warped = warp_region(image, field, cv::Rect(0, 0, 60, 60), Interpolator::kLanczos3);
  for (const int y : {4, 12, 18, 25, 33, 38, 45}) {
    for (const int x : {4, 12, 15, 20, 33, 45, 50, 55}) {
      const double u = 0.1 * (std::clamp(x, 15, 45) - 25), v = 0.05 * (std::clamp(y, 15, 40) - 25);
      EXPECT_NEAR(warped.at<float>(y, x), smooth(x + u, y + v), 2e-3) << x << ", " << y;
    }
  }
  EXPECT_EQ(nodes_under(cv::Rect(52, 45, 5, 5), field.grid), cv::Rect(1, 0, 2, 2)) << "the outermost piece's nodes";
}

}  // namespace
}  // namespace bosfuse::fusion
