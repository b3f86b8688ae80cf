#include "fusion/window_correlator.h"

#include <gtest/gtest.h>

#include <cmath>

namespace bosfuse::fusion {
namespace {

cv::Mat random_image(int size, int seed) {
  cv::Mat image(size, size, CV_32F);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0.0, 1.0);
  return image;
}

TEST(WindowCorrelator, DirectAndFftGiveTheSamePlane) {
  const cv::Mat image = random_image(64, 1);
  for (const auto pairing : {WindowPairing::kSearchArea, WindowPairing::kEqualWindows}) {
    for (const int radius : {1, 3, 5}) {
      WindowCorrelator correlator;
      CorrelationPlane direct, fft;
      const cv::Mat window = image(cv::Rect(20, 20, 16, 16));
      const cv::Mat patch = image(cv::Rect(20 - radius + 1, 20 - radius, 16 + 2 * radius, 16 + 2 * radius));
      correlator.correlate(window, patch, radius, CorrelationMethod::kDirect, direct, pairing);
      correlator.correlate(window, patch, radius, CorrelationMethod::kFft, fft, pairing);
      ASSERT_EQ(direct.value.size(), fft.value.size());
      for (std::size_t i = 0; i < direct.value.size(); ++i) EXPECT_NEAR(direct.value[i], fft.value[i], 1e-5);
    }
  }
}

TEST(WindowCorrelator, FindsTheShiftWithCorrelationOne) {
  const cv::Mat image = random_image(64, 2);
  WindowCorrelator correlator;
  CorrelationPlane plane;
  // The patch starts 1 px left of and 2 px below where an unshifted search
  // would start, so the window's content appears at shift (+1, −2) in it.
  const int radius = 4;
  const cv::Mat window = image(cv::Rect(24, 24, 16, 16));
  const cv::Mat patch = image(cv::Rect(24 - radius - 1, 24 - radius + 2, 16 + 2 * radius, 16 + 2 * radius));
  correlator.correlate(window, patch, radius, CorrelationMethod::kDirect, plane);
  EXPECT_NEAR(plane.at(1, -2), 1.0, 1e-6);
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (dx != 1 || dy != -2) {
        EXPECT_LT(plane.at(dx, dy), 0.5);
      }
    }
  }
}

// A plane of radius 5 holding a Gaussian peak of σ `sigma_px` at the
// centre, plus `extra` added at (dx, dy) when given.
CorrelationPlane gaussian_plane(double sigma_px, int dx = 0, int dy = 0, double extra = 0) {
  CorrelationPlane plane;
  plane.radius = 5;
  plane.value.resize(static_cast<std::size_t>(plane.side() * plane.side()));
  for (int y = -5; y <= 5; ++y) {
    for (int x = -5; x <= 5; ++x) {
      double v = std::exp(-(x * x + y * y) / (2 * sigma_px * sigma_px));
      if (x == dx && y == dy) v += extra;
      plane.value[static_cast<std::size_t>((y + 5) * plane.side() + x + 5)] = v;
    }
  }
  return plane;
}

// A 6 px dot's correlation peak (σ ≈ 2.1 px) still stands at 0.64 of its
// height 2 px out, outside the 3×3: the highest value there is its own
// flank, not a second peak. separate_ratio looks for a second peak.
TEST(WindowCorrelator, ABroadPeaksFlankIsNoSecondPeak) {
  const CorrelationPeak broad = find_peak(gaussian_plane(2.1));
  EXPECT_EQ(broad.dx, 0);
  EXPECT_EQ(broad.dy, 0);
  EXPECT_LT(broad.ratio, 1.6);                     // the flank read as a second peak
  EXPECT_NEAR(broad.separate_ratio, 100.0, 1e-9);  // none: 1 over the 0.01 floor
  // A separate peak of 0.5 on the flank at (4, −4): the ratio is to it.
  const CorrelationPlane two = gaussian_plane(2.1, 4, -4, 0.5);
  const CorrelationPeak peak = find_peak(two);
  EXPECT_NEAR(peak.separate_ratio, 1.0 / two.at(4, -4), 1e-12);
  EXPECT_GT(peak.separate_ratio, 1.5);
  // Two peaks of about the same height are ambiguous either way.
  const CorrelationPeak even = find_peak(gaussian_plane(0.8, -4, 3, 0.95));
  EXPECT_LT(even.separate_ratio, 1.1);
  EXPECT_NEAR(even.separate_ratio, even.ratio, 1e-12);
}

TEST(WindowCorrelator, IdenticalEqualWindowsGiveASymmetricPeak) {
  const cv::Mat image = random_image(32, 3);
  WindowCorrelator correlator;
  CorrelationPlane plane;
  correlator.correlate(image(cv::Rect(8, 8, 16, 16)), image(cv::Rect(6, 6, 20, 20)), 2, CorrelationMethod::kDirect,
                       plane, WindowPairing::kEqualWindows);
  EXPECT_NEAR(plane.at(0, 0), 1.0, 1e-6);
  EXPECT_NEAR(plane.at(1, 0), plane.at(-1, 0), 1e-6);
  EXPECT_NEAR(plane.at(0, 1), plane.at(0, -1), 1e-6);
}

TEST(WindowCorrelator, FlatWindowsGiveZeroNotNan) {
  const cv::Mat flat(24, 24, CV_32F, cv::Scalar(0.7f));
  WindowCorrelator correlator;
  CorrelationPlane plane;
  correlator.correlate(flat(cv::Rect(4, 4, 16, 16)), flat, 4, CorrelationMethod::kAuto, plane);
  for (double v : plane.value) EXPECT_EQ(v, 0.0);
  EXPECT_EQ(plane.reference_std, 0.0);
}

TEST(WindowCorrelator, AutoPicksDirectForSmallSearchesAndFftForLargeOnes) {
  EXPECT_EQ(WindowCorrelator::cheaper_method(16, 2), CorrelationMethod::kDirect);
  EXPECT_EQ(WindowCorrelator::cheaper_method(64, 16), CorrelationMethod::kFft);
}

}  // namespace
}  // namespace bosfuse::fusion
