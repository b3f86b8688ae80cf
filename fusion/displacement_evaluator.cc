#include "fusion/displacement_evaluator.h"

#include <cmath>
#include <stdexcept>

#include "fusion/memory_budget.h"

namespace bosfuse::fusion {

std::string EvaluatorOptions::Validate() const {
  return method == Method::kCrossCorrelation ? xcorr.Validate() : flow.Validate();
}

void EvaluatorOptions::set_grid(int window_px, int step_px, cv::Rect roi) {
  xcorr.window_px = flow.window_px = window_px;
  xcorr.step_px = flow.step_px = step_px;
  xcorr.roi = flow.roi = roi;
}

DisplacementEvaluator::DisplacementEvaluator(const cv::Mat& reference, const EvaluatorOptions& options,
                                             const cv::Mat& mask)
    : reference_(reference), mask_(mask), options_(options) {
  if (options.method == Method::kCrossCorrelation) {
    xcorr_.emplace(reference, options.xcorr, mask);
  } else if (const std::string problem = options.Validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
}

void DisplacementEvaluator::check_memory() const {
  if (xcorr_) {
    check_xcorr_memory(reference_, mask_, options_.xcorr);
  } else {
    check_flow_memory(reference_, mask_, options_.flow);
  }
}

GridGeometry DisplacementEvaluator::grid() const {
  const auto grid_of = [&](const auto& method) {
    return evaluation_grid(effective_roi(method.roi, reference_.size()), method.window_px, method.step_px);
  };
  return xcorr_ ? grid_of(options_.xcorr) : grid_of(options_.flow);
}

EvaluationResult DisplacementEvaluator::evaluate(const cv::Mat& measurement) {
  if (xcorr_) return xcorr_->evaluate(measurement);
  return evaluate_flow(reference_, measurement, options_.flow, mask_);
}

EvaluationResult DisplacementEvaluator::probe(const cv::Mat& measurement, const std::vector<cv::Point2d>& points) {
  if (xcorr_) return xcorr_->probe(measurement, points);
  // Flow is dense anyway: evaluate a grid with step 1 restricted to the
  // points' windows would cost the same; take the nearest grid vector.
  EvaluationResult full = evaluate_flow(reference_, measurement, options_.flow, mask_);
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
    if (best && best_distance <= options_.flow.step_px) vec = *best;
    result.field.vectors.push_back(vec);
  }
  count_flags(result.field, result.summary);
  return result;
}

EvaluationResult evaluate_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                       const EvaluatorOptions& options, const cv::Mat& mask) {
  if (options.method == Method::kCrossCorrelation) return evaluate_xcorr(reference, measurement, options.xcorr, mask);
  return evaluate_flow(reference, measurement, options.flow, mask);
}

EvaluationResult probe_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                    const std::vector<cv::Point2d>& points, const EvaluatorOptions& options,
                                    const cv::Mat& mask) {
  return DisplacementEvaluator(reference, options, mask).probe(measurement, points);
}

}  // namespace bosfuse::fusion
