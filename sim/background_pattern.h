#pragma once
// A random-dot background for BOS, as the paper used: dots of one size at
// random positions (overlaps allowed, as with a real random pattern), each
// with a grey level drawn from a list (0, 43, 86, 128 by default) on a white
// background. Use generate_pattern for the dot list (the same list renders
// the printable pattern and the synthetic image pairs of synthetic_pair.h),
// render_pattern for the print/reference image, and write_pattern_image to
// save it with its resolution so it prints at the intended dot size.
//
// Coverage is the fraction of the area covered by at least one dot; for
// randomly placed discs of area a, N dots on area A cover 1 − exp(−N·a/A),
// so N = −ln(1 − coverage)·A/a.

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace bosfuse::sim {

struct Dot {
  double x_px = 0;  // centre, image coordinates (origin at the top-left pixel's centre)
  double y_px = 0;
  int grey = 0;  // 0..255
};

struct PatternOptions {
  int width_px = 1024;
  int height_px = 768;
  double dot_diameter_px = 3;  // used unless dot_diameter_mm > 0
  double dot_diameter_mm = 0;  // with dpi: the printed dot size
  double dpi = 300;            // printing resolution, stored in the image file
  double coverage = 0.5;       // 0 < coverage < 1
  std::vector<int> grey_levels{0, 43, 86, 128};
  int background_grey = 255;
  std::uint64_t seed = 1;

  std::string Validate() const;  // empty when valid
  double diameter_px() const;    // from mm and dpi when given in mm
};

struct BackgroundPattern {
  cv::Size size;
  double dot_diameter_px = 3;
  int background_grey = 255;
  double dpi = 300;
  std::vector<Dot> dots;
};

BackgroundPattern generate_pattern(const PatternOptions& options);

// The pattern as an 8-bit image with hard-edged discs, each pixel the
// area-weighted grey of what covers it (8×8 samples per pixel).
cv::Mat render_pattern(const BackgroundPattern& pattern);

// PNG (with a pHYs chunk) or TIFF (X/Y resolution tags), by extension;
// both carry `dpi`, written through storage::PartialFile (in place only
// once whole; never one of a run's own files). Throws std::runtime_error
// on failure.
void write_pattern_image(const std::filesystem::path& path, const cv::Mat& image, double dpi);

// The resolution stored in a PNG's pHYs chunk, in dots per inch; 0 if none.
double read_png_dpi(const std::filesystem::path& path);

}  // namespace bosfuse::sim
