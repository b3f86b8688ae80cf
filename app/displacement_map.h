#pragma once
// A displacement map like the paper's figures: the magnitude of the shift in
// colour, contour lines at a chosen spacing, and a labelled colour bar.
// Vectors that are not measurements (masked, no texture...) are grey.

#include <opencv2/core.hpp>

#include "fusion/displacement_field.h"

namespace bosfuse::app {

struct MapOptions {
  double contour_spacing_px = 0.1;  // 0: no contours
  int target_width_px = 800;        // the map is scaled to about this width
};

// A BGR image; throws if the field is empty.
cv::Mat draw_displacement_map(const fusion::DisplacementField& field, const MapOptions& options);

// A grey-scale quantity (e.g. the local Q_mod, range 0..1) with a colour bar.
cv::Mat draw_scalar_map(const cv::Mat& values, double low, double high, const char* label);

}  // namespace bosfuse::app
