#pragma once
// A synthetic BOS pair (sim/synthetic_pair.h) written as two image files:
// the background, and the background shifted uniformly by (u, v) px. For
// tests that evaluate files rather than images in memory.

#include <opencv2/imgcodecs.hpp>
#include <string>

#include "sim/synthetic_pair.h"

namespace bosfuse::testing {

// An empty `reference_path` writes only the measurement; `seed` picks the background.
inline void write_shifted_pair(const std::string& reference_path, const std::string& measurement_path, cv::Size size,
                               double u_px, double v_px, std::uint64_t seed = 1) {
  sim::PairOptions options;
  options.pattern.width_px = size.width, options.pattern.height_px = size.height, options.pattern.seed = seed;
  options.field = sim::DisplacementModel::uniform(u_px, v_px);
  const auto pair = sim::render_pair(options);
  if (!reference_path.empty()) cv::imwrite(reference_path, pair.reference);
  cv::imwrite(measurement_path, pair.measurement);
}

}  // namespace bosfuse::testing
