#pragma once
// The synthetic pairs of issue 30's hard scenes, shared by bos_bench and
// write_bench_pairs (which writes them to files for other PIV programs,
// bench/openpiv_compare.py): the low-contrast 10-bit camera and the
// 768×768 pair of a large uniform shift. One definition, so that a
// comparison evaluates the very pair the benchmark does.

#include <cstdint>
#include <opencv2/core.hpp>

#include "sim/synthetic_pair.h"

namespace bosfuse::bench {

// The low-contrast camera: the dots' contrast scaled to 0.12 of
// full around mid-grey, `noise` of full scale, quantised to 10 bits (stored
// in 16, as such cameras' frames are).
inline cv::Mat low_contrast_exposure(const cv::Mat& dots, double noise, std::uint64_t seed) {
  cv::Mat image = 0.5 + 0.12 * (dots - 0.5);
  cv::Mat grain(image.size(), CV_64F);
  cv::RNG(seed).fill(grain, cv::RNG::NORMAL, 0.0, noise);
  image += grain;
  cv::Mat levels;
  image.convertTo(levels, CV_16U, 1023.0);  // rounds and saturates to 0..1023 (the 10 bits)
  cv::min(levels, 1023, levels);
  return levels * 64;
}

inline constexpr int kLowContrastSize = 512;

// The i-th (0..2) low-contrast pair: 512×512, 3 px dots, a uniform
// sub-pixel shift (low_contrast_shift(i)), its own background seed.
inline cv::Point2d low_contrast_shift(int i) {
  const cv::Point2d shifts[] = {{0.3, -0.2}, {0.75, 0.45}, {-0.55, 0.9}};
  return shifts[i];
}

inline sim::SyntheticPair low_contrast_pair(int i, double noise) {
  const std::uint64_t seed = 3 + static_cast<std::uint64_t>(i);
  sim::PatternOptions pattern;
  pattern.width_px = pattern.height_px = kLowContrastSize;
  pattern.seed = seed;
  const auto dots = sim::generate_pattern(pattern);
  const cv::Point2d shift = low_contrast_shift(i);
  sim::SyntheticPair pair;
  pair.truth = sim::DisplacementModel::uniform(shift.x, shift.y);
  pair.reference = low_contrast_exposure(sim::render_dots(dots, nullptr), noise, seed * 2 + 1);
  pair.measurement = low_contrast_exposure(sim::render_dots(dots, &pair.truth), noise, seed * 2 + 2);
  return pair;
}

// The 768×768 pair of a uniform shift (u, v) px: 3 px dots, 50 % coverage.
inline sim::SyntheticPair large_shift_pair(double u_px, double v_px) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 768;
  options.pattern.dot_diameter_px = 3;
  options.pattern.coverage = 0.5;
  options.pattern.seed = 11;
  options.field = sim::DisplacementModel::uniform(u_px, v_px);
  return sim::render_pair(options);
}

}  // namespace bosfuse::bench
