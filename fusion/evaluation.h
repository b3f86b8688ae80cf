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
  std::size_t beyond_search = 0;
  // The first pass's search (cross-correlation; 0 for other methods): its
  // bound and window, whether the scene's sample set them (search_range.h)
  // (or as a processing stored it) and widened them, or found displacements past the widest it allows;
  // and of the first pass's measured windows (textured, unmasked), how
  // many peaked on the bound.
  double max_shift_px = 0;
  int first_window_px = 0;
  bool search_from_scene = false;
  bool search_stored = false;  // from the scene, as an earlier evaluation found it (the sample not run again)
  bool search_widened = false;
  bool search_beyond_reach = false;
  std::size_t first_pass_windows = 0;
  std::size_t first_pass_on_bound = 0;
  double seconds = 0;
  // What the evaluation has to tell, for the caller to log (fusion/ logs
  // nothing), each in the order it arose: warnings (a colour image
  // converted, a search bound hit) at warning level, and notes of how it
  // went (the memory it needs, the search found, the refinement's
  // threshold) at debug level.
  std::vector<std::string> warnings;
  std::vector<std::string> notes;

  std::string BriefReport() const;
  // Of the first pass's measured windows, the fraction on the search bound.
  double on_bound_fraction() const;
};

// Above this fraction of the first pass's windows on the search bound, an
// evaluation says so (search_bound_warning).
inline constexpr double kOnBoundWarningFraction = 0.02;

// The warning, with its fix, when more than kOnBoundWarningFraction of the
// first pass's windows peaked on the search bound or the scene's
// displacements lie past the widest search it allows; empty otherwise.
std::string search_bound_warning(const EvaluationSummary& summary);

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
