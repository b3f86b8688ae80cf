#pragma once
// One entry point for both displacement methods, so callers (the command
// line, benchmarks, the fusion of frames and thermocouples) choose the method
// by an option and get the same kind of result on the same grid.
//   kCrossCorrelation — cross_correlation.h: the accurate default;
//   kOpticalFlow      — optical_flow.h: dense flow averaged per window.
// Either method evaluates the images after the preprocessing the options
// name (preprocess.h; none by default).

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "fusion/cross_correlation.h"
#include "fusion/optical_flow.h"
#include "fusion/preprocess.h"

namespace bosfuse::fusion {

enum class Method { kCrossCorrelation, kOpticalFlow };

struct EvaluatorOptions {
  Method method = Method::kCrossCorrelation;
  XcorrOptions xcorr;
  FlowOptions flow;
  PreprocessOptions preprocess;  // applied to the reference once and to every measurement

  std::string Validate() const;  // empty when valid
  // Window, step and ROI set for both methods at once.
  void set_grid(int window_px, int step_px, cv::Rect roi = {});
};

// One reference against many measurements (the frames of a run) with
// either method; the command that processes a run holds one. With
// cross-correlation it is an XcorrEvaluator, whose preparation of the
// reference and whose buffers carry over from frame to frame; optical flow
// keeps nothing between frames (yet). Results equal evaluate_displacement /
// probe_displacement, which are one-shot wrappers around it. Shares the
// reference's and mask's pixels: do not write into them while it lives.
// Bad options, reference or mask raise std::invalid_argument here; a bad
// measurement, in evaluate / probe. With preprocessing the evaluator holds
// the preprocessed reference (its own pixels) and preprocesses each
// measurement whole, probes too (a 16 MP frame: docs/BENCHMARKS.md).
class DisplacementEvaluator {
 public:
  DisplacementEvaluator(const cv::Mat& reference, const EvaluatorOptions& options, const cv::Mat& mask = {});

  // Throws InsufficientMemory (memory_budget.h) when a full-field
  // evaluation needs more than this process can get. evaluate() checks it
  // at its first frame; a caller that must know before it starts (a
  // sequence, whose output file is laid out first) asks here. Returns the
  // account of needed and available memory (memory_budget.h), empty when
  // nothing was checked, for the caller's log at debug level.
  std::string check_memory() const;

  EvaluationResult evaluate(const cv::Mat& measurement);
  // The cross-correlation's first-pass search (XcorrEvaluator::search_range),
  // found from `measurement` when no frame has been evaluated yet; empty for
  // optical flow and with an explicit bound.
  std::optional<SearchRange> search_range(const cv::Mat& measurement);
  // The grid of the fields evaluate() gives, known before any frame.
  GridGeometry grid() const;
  // See probe_displacement below.
  EvaluationResult probe(const cv::Mat& measurement, const std::vector<cv::Point2d>& points);

 private:
  // Preprocessed as the reference was; its colour conversion warned of into `warnings`.
  cv::Mat prepared(const cv::Mat& measurement, std::vector<std::string>& warnings) const;
  // `result` with the warnings of the reference's preprocessing (the first
  // result only) and of the measurement's before its own.
  EvaluationResult warned(std::vector<std::string> preprocessing_warnings, EvaluationResult result);

  cv::Mat reference_, mask_;  // reference_: preprocessed
  EvaluatorOptions options_;
  std::vector<std::string> reference_warnings_;  // the reference's preprocessing's, until the first result
  std::optional<XcorrEvaluator> xcorr_;  // with Method::kCrossCorrelation
};

EvaluationResult evaluate_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                       const EvaluatorOptions& options, const cv::Mat& mask = {});

// Probe mode: cross-correlation evaluates only the windows at the points;
// optical flow computes the dense flow and averages it over those windows.
EvaluationResult probe_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                    const std::vector<cv::Point2d>& points, const EvaluatorOptions& options,
                                    const cv::Mat& mask = {});

}  // namespace bosfuse::fusion
