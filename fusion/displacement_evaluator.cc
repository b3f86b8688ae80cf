#include "fusion/displacement_evaluator.h"

#include <cmath>
#include <stdexcept>

namespace bosfuse::fusion {

std::string EvaluatorOptions::Validate() const {
  return method == Method::kCrossCorrelation ? xcorr.Validate() : flow.Validate();
}

void EvaluatorOptions::set_grid(int window_px, int step_px, cv::Rect roi) {
  xcorr.window_px = flow.window_px = window_px;
  xcorr.step_px = flow.step_px = step_px;
  xcorr.roi = flow.roi = roi;
}

EvaluationResult evaluate_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                       const EvaluatorOptions& options, const cv::Mat& mask) {
  if (options.method == Method::kCrossCorrelation) return evaluate_xcorr(reference, measurement, options.xcorr, mask);
  return evaluate_flow(reference, measurement, options.flow, mask);
}

EvaluationResult probe_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                    const std::vector<cv::Point2d>& points, const EvaluatorOptions& options,
                                    const cv::Mat& mask) {
  if (options.method == Method::kCrossCorrelation) {
    return probe_xcorr(reference, measurement, points, options.xcorr, mask);
  }
  // Flow is dense anyway: evaluate a grid with step 1 restricted to the
  // points' windows would cost the same; take the nearest grid vector.
  EvaluationResult full = evaluate_flow(reference, measurement, options.flow, mask);
  EvaluationResult result;
  result.summary = full.summary;
  result.field.rows = 1;
  result.field.cols = static_cast<int>(points.size());
  for (const auto& p : points) {
    const DisplacementVector* best = nullptr;
    double best_distance = 1e300;
    for (const auto& v : full.field.vectors) {
      const double d = std::hypot(v.x_px - p.x, v.y_px - p.y);
      if (d < best_distance) {
        best_distance = d;
        best = &v;
      }
    }
    DisplacementVector vec{p.x, p.y, 0, 0, 0, VectorFlag::kOutOfRoi};
    if (best && best_distance <= options.flow.step_px) vec = *best;
    result.field.vectors.push_back(vec);
  }
  count_flags(result.field, result.summary);
  return result;
}

}  // namespace bosfuse::fusion
