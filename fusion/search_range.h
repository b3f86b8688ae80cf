#pragma once
// The first pass's search bound and window, found from the scene before a
// cross-correlation evaluation (cross_correlation.h) runs. A sparse sample
// of windows spread over the region of interest is correlated at the bound
// the options give; when more than a few of them peak on that bound or show
// no clear peak, the displacement may lie beyond it, and the same sample is
// correlated again with large windows and a wide search (a quarter of the
// window, the PIV rule). The first pass then searches as far as the largest
// displacement found there, plus a margin, with a window four times that.
// A scene whose sample peaks well inside the bound costs only the sample.
//
// Use it once per reference and setting (the first measured frame of a
// run); later frames reuse what it found (pipeline/processing_settings.h
// stores it). An explicit bound (`bosfuse evaluate --max-shift`) skips it.

#include <opencv2/core.hpp>
#include <string>

namespace bosfuse::fusion {

struct SearchRangeOptions {
  int sample_windows = 64;  // windows in the sparse sample (a square grid over the ROI)
  // Of the textured sample windows, the fraction that peak on the bound or
  // show no clear peak above which the search is widened. A still scene
  // shows a few in its untextured corners; a shift past the bound, most.
  double widen_fraction = 0.05;
  // Of the widened sample, the fraction without a clear peak above which
  // even the widest search is short of the displacement. Below it, the
  // unclear windows are the scene's (dark, glare, blur), not a shift: the
  // clear ones say how far to search.
  double beyond_reach_fraction = 0.5;
  int wide_window_px = 64;      // the widened sample's window (less when the ROI is small)
  double margin_px = 2;         // added to the largest displacement found
  double min_peak_ratio = 1.5;  // a sample peak below this ratio to the second is not clear

  std::string Validate() const;  // empty when valid
};

// What the search started from and found.
struct SearchRange {
  double given_max_shift_px = 0;  // the bound it started from
  double max_shift_px = 0;        // the first pass's bound
  int first_window_px = 0;  // the first pass's window
  bool widened = false;     // the sample's peaks lay on the given bound; the bound was raised
  // Even the widest search the scene allows saw no clear peak in most of the
  // sample: displacements beyond ±max_shift_px (or images that do not match).
  bool beyond_reach = false;
  int sampled = 0;            // textured sample windows at the given bound
  int on_bound = 0;           // of them, on the bound or without a clear peak
  double largest_px = 0;      // largest |u| or |v| the widened sample found (0 when not widened)
  std::string Describe() const;  // one line for the summary
};

// The sample's images: CV_32F, [0, 1], of the same size; `excluded` CV_8U
// (non-zero excluded) or empty. `max_shift_px` and `first_window_px` are
// the bounds to start from; the result keeps them unless the sample says
// otherwise, and never returns a smaller bound or window. `window_px` is
// the final window (the first never falls below it).
struct SearchStart {
  double max_shift_px = 4;
  int first_window_px = 16;
  int window_px = 16;
  double min_texture_std = 0.002;
  double max_masked_fraction = 0.5;
};

SearchRange find_search_range(const cv::Mat& reference, const cv::Mat& measurement, cv::Rect roi,
                              const cv::Mat& excluded, const SearchStart& start, const SearchRangeOptions& options);

}  // namespace bosfuse::fusion
