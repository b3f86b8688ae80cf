#pragma once
// What every displacement evaluator (cross-correlation, optical flow) shares:
// the grid of window centres it reports on, and the result it returns — the
// field plus a Summary of how it was obtained. Two methods evaluated with the
// same window and step report on the same grid, so they can be compared
// vector by vector.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fusion/displacement_field.h"
#include "fusion/field_warp.h"

namespace bosfuse::fusion {

struct EvaluationSummary {
  std::string method;  // "xcorr", "flow-dis", ...
  int passes_run = 0;
  std::vector<int> window_px_per_pass;
  bool converged = false;     // stopped because a pass changed nothing
  double last_change_px = 0;  // max |Δu|,|Δv| of the last refinement pass
  // Of the windows not out of the ROI, the fraction the refinement passes
  // evaluated: 1 without adaptive refinement, 0 without a refinement pass.
  double refined_fraction = 0;
  std::size_t vectors = 0;
  std::size_t valid = 0;
  std::size_t outliers_replaced = 0;
  std::size_t no_texture = 0;
  std::size_t masked = 0;
  std::size_t out_of_roi = 0;
  std::size_t no_peak = 0;
  double seconds = 0;

  std::string BriefReport() const;
};

struct EvaluationResult {
  DisplacementField field;
  EvaluationSummary summary;
};

// The region of interest clipped to the image; an empty `roi` means the whole
// image. Throws std::invalid_argument if it lies outside the image or has a
// negative size. Any int rect is safe: the arithmetic is 64-bit.
cv::Rect effective_roi(cv::Rect roi, cv::Size image_size);

// Window centres for windows of `window_px` placed every `step_px` inside
// `roi`, starting at its top-left corner.
GridGeometry evaluation_grid(cv::Rect roi, int window_px, int step_px);

// An empty field on `grid`, every vector kOk with its centre set.
DisplacementField field_on_grid(const GridGeometry& grid);

// Fills the counts of `summary` from `field`.
void count_flags(const DisplacementField& field, EvaluationSummary& summary);

}  // namespace bosfuse::fusion
