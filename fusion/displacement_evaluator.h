#pragma once
// One entry point for both displacement methods, so callers (the command
// line, benchmarks, the fusion of frames and thermocouples) choose the method
// by an option and get the same kind of result on the same grid.
//   kCrossCorrelation — cross_correlation.h: the accurate default;
//   kOpticalFlow      — optical_flow.h: dense flow averaged per window.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fusion/cross_correlation.h"
#include "fusion/optical_flow.h"

namespace bosfuse::fusion {

enum class Method { kCrossCorrelation, kOpticalFlow };

struct EvaluatorOptions {
  Method method = Method::kCrossCorrelation;
  XcorrOptions xcorr;
  FlowOptions flow;

  std::string Validate() const;  // empty when valid
  // Window, step and ROI set for both methods at once.
  void set_grid(int window_px, int step_px, cv::Rect roi = {});
};

EvaluationResult evaluate_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                       const EvaluatorOptions& options, const cv::Mat& mask = {});

// Probe mode: cross-correlation evaluates only the windows at the points;
// optical flow computes the dense flow and averages it over those windows.
EvaluationResult probe_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                    const std::vector<cv::Point2d>& points, const EvaluatorOptions& options,
                                    const cv::Mat& mask = {});

}  // namespace bosfuse::fusion
