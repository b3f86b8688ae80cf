#include "fusion/image_quality.h"

#include "fusion/image_input.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "sim/background_pattern.h"

namespace bosfuse::fusion {
namespace {

cv::Mat pattern_image(int size = 128) {
  sim::PatternOptions options;
  options.width_px = options.height_px = size;
  return sim::render_pattern(sim::generate_pattern(options));
}

TEST(ImageQuality, IdenticalImagesScoreOne) {
  const cv::Mat p = pattern_image();
  const auto report = assess_quality(p, p);
  EXPECT_NEAR(report.global.q_l, 1.0, 1e-12);
  EXPECT_NEAR(report.global.q_c, 1.0, 1e-12);
  EXPECT_NEAR(report.global.q_mod, 1.0, 1e-12);
  EXPECT_NEAR(report.universal_index, 1.0, 1e-9);
  EXPECT_NEAR(report.mean_local_q_mod, 1.0, 1e-9);
}

TEST(ImageQuality, MatchesTheFormulasWithTheSampleStandardDeviation) {
  // Two 2×2 images computed by hand: x = {0.2, 0.4, 0.6, 0.8}, y = x/2.
  cv::Mat x = (cv::Mat_<float>(2, 2) << 0.2f, 0.4f, 0.6f, 0.8f);
  cv::Mat y = x / 2;
  const auto q = modified_quality_index(x, y);
  const double sx = std::sqrt((0.09 + 0.01 + 0.01 + 0.09) / 3.0);  // sample σ around 0.5
  EXPECT_NEAR(q.std_image, sx, 1e-6);
  EXPECT_NEAR(q.std_reference, sx / 2, 1e-6);
  EXPECT_NEAR(q.q_l, 2 * 0.5 * 0.25 / (0.25 + 0.0625), 1e-6);  // 0.8
  EXPECT_NEAR(q.q_c, 0.8, 1e-6);                               // the same ratio for σ
  EXPECT_NEAR(q.q_mod, 0.64, 1e-6);
}

TEST(ImageQuality, LowContrastAndDarkCaptureScoreLow) {
  const cv::Mat p = pattern_image();
  cv::Mat washed;
  p.convertTo(washed, CV_8U, 0.1, 20);  // dim and flat, like the Imacon frames
  const auto report = assess_quality(washed, p);
  EXPECT_LT(report.global.q_l, 0.5);
  EXPECT_LT(report.global.q_c, 0.3);
  EXPECT_LT(report.global.q_mod, 0.15);
  EXPECT_GT(report.global.q_mod, 0.0);
  EXPECT_LT(report.mean_local_q_mod, 0.5);
}

TEST(ImageQuality, BlurLowersContrastButNotLuminance) {
  const cv::Mat p = pattern_image();
  cv::Mat blurred;
  cv::GaussianBlur(p, blurred, cv::Size(0, 0), 2.0);
  const auto q = modified_quality_index(blurred, p);
  EXPECT_NEAR(q.q_l, 1.0, 0.01);
  EXPECT_LT(q.q_c, 0.9);
}

TEST(ImageQuality, FlatImagesAreDefinedNotNan) {
  const cv::Mat white(32, 32, CV_8U, cv::Scalar(255)), black(32, 32, CV_8U, cv::Scalar(0));
  const auto same = assess_quality(white, white);
  EXPECT_DOUBLE_EQ(same.global.q_mod, 1.0);
  EXPECT_DOUBLE_EQ(same.universal_index, 1.0);
  const auto opposite = assess_quality(black, white);
  EXPECT_DOUBLE_EQ(opposite.global.q_l, 0.0);
  EXPECT_TRUE(std::isfinite(opposite.universal_index));
  const auto flat_vs_texture = assess_quality(white, pattern_image(32));
  EXPECT_DOUBLE_EQ(flat_vs_texture.global.q_c, 0.0);
  EXPECT_TRUE(std::isfinite(flat_vs_texture.universal_index));
}

TEST(ImageQuality, ReferenceOfAnotherSizeIsResizedForTheMap) {
  const cv::Mat p = pattern_image(256);
  cv::Mat small;
  cv::resize(p, small, cv::Size(128, 128), 0, 0, cv::INTER_AREA);
  const auto report = assess_quality(small, p);
  EXPECT_EQ(report.local_q_mod.size(), cv::Size(121, 121));
  EXPECT_GT(report.mean_local_q_mod, 0.9);
}

TEST(ImageQuality, SixteenBitImagesScaleToFullScale) {
  const cv::Mat p = pattern_image();
  cv::Mat p16;
  p.convertTo(p16, CV_16U, 257.0);
  EXPECT_NEAR(modified_quality_index(p16, p).q_mod, 1.0, 1e-6);
}

TEST(ImageQuality, MomentsOfTheStoredImageEqualThoseOfItsFloatCopy) {
  cv::Mat image8(64, 80, CV_8U), image16(64, 80, CV_16U), colour(64, 80, CV_8UC3);
  cv::randu(image8, 0, 256);
  cv::randu(image16, 0, 65536);
  cv::randu(colour, 0, 256);
  for (const cv::Mat& image : {image8, image16, colour}) {
    const cv::Mat unit = to_grey_unit_float(image, "image");
    cv::Scalar mean, std_dev;
    cv::meanStdDev(unit, mean, std_dev);
    const double n = double(unit.total());
    const GreyMoments m = grey_moments(image);
    EXPECT_NEAR(m.mean, mean[0], 1e-6);
    EXPECT_NEAR(m.std, std_dev[0] * std::sqrt(n / (n - 1)), 1e-6);
  }
  EXPECT_DOUBLE_EQ(modified_quality_index(grey_moments(image8), grey_moments(image16)).q_mod,
                   modified_quality_index(image8, image16).q_mod);
}

}  // namespace
}  // namespace bosfuse::fusion
