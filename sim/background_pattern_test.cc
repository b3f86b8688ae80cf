#include "sim/background_pattern.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <set>

#include "tests/support/temp_dir.h"

namespace bosfuse::sim {
namespace {

// Each covered pixel is as dark as the mean dot grey (64.25 for the default
// levels), so the mean brightness tells the covered area, edges included.
double covered_fraction(const cv::Mat& image) { return (255.0 - cv::mean(image)[0]) / (255.0 - 64.25); }

TEST(BackgroundPattern, CoverageIsTheFractionOfDarkArea) {
  for (const double coverage : {0.05, 0.2, 0.5}) {
    PatternOptions options;
    options.width_px = options.height_px = 512;
    options.dot_diameter_px = 4;
    options.coverage = coverage;
    const double measured = covered_fraction(render_pattern(generate_pattern(options)));
    EXPECT_NEAR(measured, coverage, 0.01 + 0.05 * coverage) << coverage;
  }
}

TEST(BackgroundPattern, DotsUseTheGreyLevelsOnWhite) {
  PatternOptions options;
  options.dot_diameter_px = 8;
  options.coverage = 0.2;
  const BackgroundPattern pattern = generate_pattern(options);
  std::set<int> greys;
  for (const Dot& d : pattern.dots) greys.insert(d.grey);
  EXPECT_EQ(greys, (std::set<int>{0, 43, 86, 128}));
  const cv::Mat image = render_pattern(pattern);
  double max_value = 0;
  cv::minMaxLoc(image, nullptr, &max_value);
  EXPECT_EQ(max_value, 255);
}

TEST(BackgroundPattern, DotSizeInMillimetresFollowsTheDpi) {
  PatternOptions options;
  options.dot_diameter_mm = 1.0;
  options.dpi = 254;
  EXPECT_NEAR(options.diameter_px(), 10.0, 1e-9);
  EXPECT_NEAR(generate_pattern(options).dot_diameter_px, 10.0, 1e-9);
}

TEST(BackgroundPattern, TheSeedMakesItReproducible) {
  PatternOptions options;
  options.width_px = options.height_px = 64;
  const cv::Mat a = render_pattern(generate_pattern(options));
  const cv::Mat b = render_pattern(generate_pattern(options));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0);
  options.seed = 2;
  EXPECT_GT(cv::norm(a, render_pattern(generate_pattern(options)), cv::NORM_INF), 0);
}

TEST(BackgroundPattern, FilesCarryTheirResolution) {
  testing::TempDir dir;
  PatternOptions options;
  options.width_px = 100;
  options.height_px = 60;
  const cv::Mat image = render_pattern(generate_pattern(options));
  const auto png = dir / "pattern.png";
  write_pattern_image(png, image, 600);
  EXPECT_NEAR(read_png_dpi(png), 600, 0.05);
  const cv::Mat back = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(back.empty());
  EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0);
  const auto tiff = dir / "pattern.tif";
  write_pattern_image(tiff, image, 300);
  EXPECT_EQ(cv::imread(tiff.string(), cv::IMREAD_UNCHANGED).size(), image.size());
  EXPECT_THROW(write_pattern_image(dir / "pattern.bmp", image, 300), std::runtime_error);
}

TEST(BackgroundPattern, BadOptionsAreNamed) {
  PatternOptions options;
  options.coverage = 1.5;
  EXPECT_NE(options.Validate().find("coverage"), std::string::npos);
  options = {};
  options.grey_levels = {0, 300};
  EXPECT_NE(options.Validate().find("300"), std::string::npos);
  options = {};
  options.width_px = 0;
  EXPECT_THROW(generate_pattern(options), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::sim
