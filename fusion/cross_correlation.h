#pragma once
// Multipass cross-correlation of interrogation windows, the standard way to
// turn a BOS (or PIV) image pair into a displacement field. Use it when you
// need the field at window resolution with a per-vector quality measure
// (peak ratio) and outlier handling; use probe_xcorr when you only need the
// shift at a few points (thermocouple positions) of many frames.
//
// Pass 1 correlates reference windows against the measurement within
// ±max_shift_px, which a sample of the scene widens, with a larger first
// window, when its peaks lie on that bound (search_range.h). Each later pass warps the measurement by the field so far
// (window deformation; see field_warp.h) and measures only what remains
// within ±refine_shift_px, with the window shrinking from first_window_px to
// window_px. After each pass the normalized-median test replaces outliers.
// Refinement stops early when a pass at the final window changes no vector by
// more than convergence_px. With adaptive_refinement the later passes
// evaluate (and warp for) only where the first pass saw a displacement. Windows whose reference has no texture, that lie
// under the mask, give no clear peak (kNoPeak) or peak on the search bound
// (kBeyondSearch) are skipped and flagged: never a valid vector.
//
// Images may be 8- or 16-bit, grey or colour (converted with a warning);
// input problems raise std::invalid_argument with a message naming them.

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fusion/evaluation.h"
#include "fusion/field_warp.h"
#include "fusion/outlier_filter.h"
#include "fusion/search_range.h"
#include "fusion/subpixel.h"
#include "fusion/window_correlator.h"

namespace bosfuse::fusion {

struct XcorrOptions {
  int window_px = 16;          // final interrogation window (8..128)
  int first_window_px = 0;     // first pass window; 0: the same as window_px
  int step_px = 8;             // grid spacing (window_px/2 is 50% overlap)
  int passes = 3;              // at most; fewer when refinement converges
  double max_shift_px = 4;     // largest displacement expected in the scene (see find_search_range)
  // Before the first frame, a sample of the scene says whether max_shift_px
  // (and first_window_px) must be widened (search_range.h); false: they are
  // an explicit bound, as given. Full fields only: probes search as given.
  bool find_search_range = true;
  SearchRangeOptions search;
  // What an earlier evaluation's sample found for this reference and these
  // settings (a processing stores it, pipeline/processing_settings.h): with
  // find_search_range, used as found instead of sampling the scene again.
  std::optional<SearchRange> known_search;
  double refine_shift_px = 1;  // largest residual searched after deformation
  bool deform = true;          // window deformation in passes after the first
  // Warp both images half-way instead of the measurement all the way. Costs
  // a second warp per pass and, on uniform sub-pixel shifts of 3 px dots, is
  // worse (bias 0.0055 against 0.0028 px at IW 16); kept for comparison.
  bool symmetric_deformation = false;
  bool coarse_first_pass = true;  // first pass on every other node (when 2·step ≤ window)
  bool smooth_predictor = true;   // 3×3 binomial smoothing between passes; keeps deformation stable
  // The deformation's interpolation. The prefiltered quintic B-spline: the
  // demo's probes (shifts 0.1 → 0.025 px, 1 % noise) read k +0.7 % high
  // with Lanczos-3, whose position error is not proportional to the shift,
  // and +0.2 % with it (docs/UNCERTAINTY.md), at Lanczos-3's 6×6 taps.
  Interpolator interpolator = Interpolator::kBSpline5;
  // Cubic deformation (16 instead of 36 taps) before the last pass: cheaper,
  // but the last pass then starts from a 0.03 px-biased predictor and ends
  // with about twice the bias (0.005 instead of 0.0025 px at IW 16).
  bool fast_early_passes = false;
  SubpixelEstimator subpixel = SubpixelEstimator::kGaussian2dFit;  // first pass (and all without deformation)
  // After deformation the peak sits at ~0, where the 3-point fit does not
  // lock and, using 5 instead of 9 values, is less noisy: 0.0097 against
  // 0.0106 px RMS at IW 16, 1 % noise (docs/BENCHMARKS.md).
  SubpixelEstimator refinement_subpixel = SubpixelEstimator::kGaussian3Point;
  CorrelationMethod correlation = CorrelationMethod::kAuto;
  OutlierOptions outliers;
  bool replace_outliers = true;
  double min_texture_std = 0.002;    // of full scale; the 8-bit equivalent is 0.5 grey level
  // A first-pass peak whose ratio to the second peak (the highest local
  // maximum outside its 3×3; CorrelationPeak::separate_ratio) is below this
  // is not told from the plane's noise: kNoPeak. On 3 px dots
  // with 1 % noise, 16 px windows' true peaks are at 1.6 or more, while
  // those of a shift past the search are at 1.2 (median) to 3. A refinement
  // pass's vector is valid only where most first-pass windows around it
  // measured: a predictor interpolated over failures is noise.
  double min_peak_ratio = 1.5;
  double max_masked_fraction = 0.5;  // of a window's pixels
  double convergence_px = 1e-3;      // 0: always run all passes
  cv::Rect roi;                      // empty: the whole image
  // Probe mode: grid nodes on each side of a probe evaluated with it, so the
  // outlier test and the deformation have neighbours. -1: as many as the
  // full field's value at that point depends on (then the probe equals the
  // full field there, away from the image edges, when convergence_px is 0).
  int probe_context_nodes = 1;
  // Adaptive refinement (fusion/adaptive_refinement.h): passes 2…n evaluate
  // only the nodes where the first pass found a displacement or gradient
  // above adaptive_threshold × its own noise floor, with the nodes around
  // them those depend on; the rest keep the first pass's (interpolated)
  // value, averaged over the unrefined nodes within about
  // adaptive_smoothing_nodes (σ; 0: as it is), and marked first_pass_only.
  // Probes ignore it (they are local already).
  bool adaptive_refinement = false;
  double adaptive_threshold = 4;
  double adaptive_smoothing_nodes = 2;
  // σu, σv of every vector the final pass measured, by correlation
  // statistics on its windows (vector_uncertainty.h); a replaced outlier
  // gets its neighbours' spread. Only when the final pass deforms (passes
  // ≥ 2 and deform); otherwise, or off, σ stays 0, "not estimated".
  bool estimate_uncertainty = true;

  std::string Validate() const;  // empty when valid
  std::vector<int> window_px_per_pass() const;
  int search_radius_px(int pass) const;  // including the margin the sub-pixel fit needs
  double on_bound_px(int pass) const;    // a peak further out than this in either axis is kBeyondSearch
  int exact_probe_context_nodes() const;
};

// Evaluates many measurements (the frames of a run) against one reference
// with the same options and mask. What does not depend on the measurement
// is prepared once, at the first frame: the reference as float, the mask and
// its integral, and every window's mean and energy. What does is kept for
// the next frame: the measurement's float image and the warped images (the
// same buffers, so a 16 MP frame does not page-fault 200 MB of fresh
// memory), and the correlators' scratch (per thread). Results equal those
// of evaluate_xcorr / probe_xcorr on the same images, which are one-shot
// wrappers around it.
//
// The evaluator shares the reference's and the mask's pixels (cv::Mat
// semantics): do not write into them while it lives. Not thread-safe: one
// evaluator per thread that evaluates frames (each evaluation uses all
// cores anyway). Problems with the options, reference or mask are raised by
// the constructor, problems with a measurement by evaluate / probe.
class XcorrEvaluator {
 public:
  XcorrEvaluator(const cv::Mat& reference, const XcorrOptions& options, const cv::Mat& mask = {});
  ~XcorrEvaluator();
  XcorrEvaluator(XcorrEvaluator&&) noexcept;
  XcorrEvaluator& operator=(XcorrEvaluator&&) noexcept;

  EvaluationResult evaluate(const cv::Mat& measurement);

  // The first pass's search for this reference: with find_search_range,
  // what the scene's sample found (or known_search) at the first frame, or
  // here, from `measurement`, when no frame was evaluated yet (the frame's
  // pixels are not kept). Empty with an explicit bound. A caller that
  // shares the work out asks here once and hands the result on as
  // known_search, so every evaluator searches as far.
  const std::optional<SearchRange>& search_range(const cv::Mat& measurement);
  const std::optional<SearchRange>& search_range() const;  // as found so far

  // As probe_xcorr below. Probes convert and warp only the few hundred
  // pixels around each point, so little is kept between frames.
  EvaluationResult probe(const cv::Mat& measurement, const std::vector<cv::Point2d>& points);

  struct State;  // opaque; named here so the implementation's helpers can take it

 private:
  std::unique_ptr<State> state_;
};

EvaluationResult evaluate_xcorr(const cv::Mat& reference, const cv::Mat& measurement, const XcorrOptions& options,
                                const cv::Mat& mask = {});

// One vector per point, each from a window centred at the point (snapped to
// the nearest window centre, which is what x_px, y_px report). A point whose
// window does not fit in the image or ROI is flagged kOutOfRoi.
EvaluationResult probe_xcorr(const cv::Mat& reference, const cv::Mat& measurement,
                             const std::vector<cv::Point2d>& points, const XcorrOptions& options,
                             const cv::Mat& mask = {});

}  // namespace bosfuse::fusion
