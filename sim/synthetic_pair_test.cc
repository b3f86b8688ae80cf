#include "sim/synthetic_pair.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace bosfuse::sim {
namespace {

PairOptions quiet(int size = 96) {
  PairOptions options;
  options.pattern.width_px = options.pattern.height_px = size;
  options.noise_std = 0;
  return options;
}

TEST(SyntheticPair, AnIntegerShiftMovesEveryPixel) {
  PairOptions options = quiet();
  options.field = DisplacementModel::uniform(2, -1);
  const auto pair = render_pair(options);
  // measurement(x + 2, y − 1) == reference(x, y), away from the edges.
  const cv::Rect inner(8, 8, 80, 80);
  const cv::Mat expected = pair.reference(inner);
  const cv::Mat moved = pair.measurement(inner + cv::Point(2, -1));
  EXPECT_LE(cv::norm(expected, moved, cv::NORM_INF), 1.0);
  EXPECT_GT(cv::norm(pair.reference(inner), pair.measurement(inner), cv::NORM_INF), 50) << "the images must differ";
}

// Intensity-weighted centroid of the darkness of a single dot.
cv::Point2d dark_centroid(const cv::Mat& image) {
  cv::Mat dark;
  image.convertTo(dark, CV_64F);
  dark = 255.0 - dark;
  const cv::Moments m = cv::moments(dark);
  return {m.m10 / m.m00, m.m01 / m.m00};
}

TEST(SyntheticPair, ASingleDotMovesByTheSubpixelShift) {
  BackgroundPattern pattern;
  pattern.size = {32, 32};
  pattern.dot_diameter_px = 4;
  pattern.dots = {{15.2, 16.7, 0}};
  const DisplacementModel shift = DisplacementModel::uniform(0.37, -0.21);
  cv::Mat ref, meas;
  render_dots(pattern, nullptr).convertTo(ref, CV_64F, 255);
  render_dots(pattern, &shift).convertTo(meas, CV_64F, 255);
  const cv::Point2d a = dark_centroid(ref), b = dark_centroid(meas);
  EXPECT_NEAR(a.x, 15.2, 1e-3);
  EXPECT_NEAR(a.y, 16.7, 1e-3);
  EXPECT_NEAR(b.x - a.x, 0.37, 1e-3);
  EXPECT_NEAR(b.y - a.y, -0.21, 1e-3);
}

TEST(SyntheticPair, NoiseBitDepthAndBlurAreApplied) {
  PairOptions options = quiet(64);
  options.bit_depth = 16;
  const auto clean = render_pair(options);
  EXPECT_EQ(clean.reference.depth(), CV_16U);
  options.noise_std = 0.02;
  const auto noisy = render_pair(options);
  cv::Mat difference;
  cv::subtract(noisy.reference, clean.reference, difference, cv::noArray(), CV_64F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(difference, mean, stddev);
  EXPECT_NEAR(stddev[0] / 65535.0, 0.02, 0.003);
  options.noise_std = 0;
  options.blur_sigma_px = 1.5;
  const auto blurred = render_pair(options);
  cv::meanStdDev(blurred.reference, mean, stddev);
  cv::Scalar sharp_mean, sharp_std;
  cv::meanStdDev(clean.reference, sharp_mean, sharp_std);
  EXPECT_LT(stddev[0], 0.8 * sharp_std[0]);
}

TEST(SyntheticPair, DisplacementModels) {
  const auto step = DisplacementModel::step(64, 1, 0);
  EXPECT_EQ(step.at(63.9, 5).x, 0.0);
  EXPECT_EQ(step.at(64, 5).x, 1.0);
  const auto wave = DisplacementModel::sinusoid(0.5, 40);
  EXPECT_NEAR(wave.at(10, 3).y, 0.5, 1e-12);
  EXPECT_NEAR(wave.window_mean(10, 3, 1).y, 0.5, 1e-12);
  const auto bump = DisplacementModel::bump_gradient(50, 50, 20, 1.5);
  EXPECT_NEAR(bump.at(70, 50).x, 1.5, 1e-12) << "the peak shift sits at the bump radius";
  EXPECT_NEAR(bump.at(50, 30).y, -1.5, 1e-12);
  EXPECT_LT(std::hypot(bump.at(50, 50).x, bump.at(50, 50).y), 1e-12);
}

TEST(SyntheticPair, BadOptionsAreNamed) {
  PairOptions options = quiet();
  options.bit_depth = 12;
  EXPECT_NE(options.Validate().find("bit depth"), std::string::npos);
  EXPECT_THROW(render_pair(options), std::invalid_argument);
}

// A 10-bit camera stored in 16 bits: 1023 levels in the top bits, clamped
// at both ends, and the noise the seed draws.
TEST(SensorImage, QuantisesToTheSensorsLevelsInTheTopBits) {
  cv::Mat image(1, 4, CV_64F);
  image.at<double>(0, 0) = 0.5;
  image.at<double>(0, 1) = 1.2;
  image.at<double>(0, 2) = -0.1;
  image.at<double>(0, 3) = 1.0 / 1023;
  const cv::Mat out = sensor_image(image.clone(), 0.0, 10, 1);
  ASSERT_EQ(out.type(), CV_16UC1);
  EXPECT_EQ(out.at<std::uint16_t>(0, 0), 512 * 64);
  EXPECT_EQ(out.at<std::uint16_t>(0, 1), 1023 * 64);
  EXPECT_EQ(out.at<std::uint16_t>(0, 2), 0);
  EXPECT_EQ(out.at<std::uint16_t>(0, 3), 64);
  cv::Mat grey(64, 64, CV_64F, cv::Scalar(0.5));
  const cv::Mat a = sensor_image(grey.clone(), 0.01, 12, 7), b = sensor_image(grey.clone(), 0.01, 12, 7);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0) << "the same seed draws the same noise";
  cv::Scalar mean, deviation;
  cv::meanStdDev(a, mean, deviation);
  EXPECT_NEAR(deviation[0] / 65535, 0.01, 0.001);
}

}  // namespace
}  // namespace bosfuse::sim
