#include "fusion/displacement_evaluator.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "fusion/image_input.h"
#include "fusion/memory_budget.h"

namespace bosfuse::fusion {

std::string EvaluatorOptions::Validate() const {
  if (std::string problem = preprocess.Validate(); !problem.empty()) return problem;
  return method == Method::kCrossCorrelation ? xcorr.Validate() : flow.Validate();
}

void EvaluatorOptions::set_grid(int window_px, int step_px, cv::Rect roi) {
  xcorr.window_px = flow.window_px = window_px;
  xcorr.step_px = flow.step_px = step_px;
  xcorr.roi = flow.roi = roi;
}

DisplacementEvaluator::DisplacementEvaluator(const cv::Mat& reference, const EvaluatorOptions& options,
                                             const cv::Mat& mask)
    : mask_(mask), options_(options) {
  if (const std::string problem = options.preprocess.Validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  // Without preprocessing the evaluators check the reference themselves.
  if (options.preprocess.method != Preprocessing::kNone) check_image_pair(reference, reference, mask);
  reference_ = preprocess(reference, options.preprocess, mask, &reference_warnings_);
  if (options.method == Method::kCrossCorrelation) {
    xcorr_.emplace(reference_, options.xcorr, mask);
  } else if (const std::string problem = options.Validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
}

std::string DisplacementEvaluator::check_memory() const {
  return xcorr_ ? check_xcorr_memory(reference_, mask_, options_.xcorr)
                : check_flow_memory(reference_, mask_, options_.flow);
}

GridGeometry DisplacementEvaluator::grid() const {
  const auto grid_of = [&](const auto& method) {
    return evaluation_grid(effective_roi(method.roi, reference_.size()), method.window_px, method.step_px);
  };
  return xcorr_ ? grid_of(options_.xcorr) : grid_of(options_.flow);
}

cv::Mat DisplacementEvaluator::prepared(const cv::Mat& measurement, std::vector<std::string>& warnings) const {
  if (options_.preprocess.method == Preprocessing::kNone) return measurement;
  // The pair's checks first, so a bad measurement is named as such.
  check_image_pair(reference_, measurement, mask_);
  return preprocess(measurement, options_.preprocess, mask_, &warnings);
}

EvaluationResult DisplacementEvaluator::warned(std::vector<std::string> preprocessing_warnings,
                                               EvaluationResult result) {
  std::vector<std::string> warnings = std::exchange(reference_warnings_, {});
  for (const auto* from : {&preprocessing_warnings, &result.summary.warnings}) {
    warnings.insert(warnings.end(), from->begin(), from->end());
  }
  result.summary.warnings = std::move(warnings);
  return result;
}

EvaluationResult DisplacementEvaluator::evaluate(const cv::Mat& measurement) {
  std::vector<std::string> warnings;
  const cv::Mat image = prepared(measurement, warnings);
  if (xcorr_) return warned(std::move(warnings), xcorr_->evaluate(image));
  return warned(std::move(warnings), evaluate_flow(reference_, image, options_.flow, mask_));
}

std::optional<SearchRange> DisplacementEvaluator::search_range(const cv::Mat& measurement) {
  if (!xcorr_) return std::nullopt;
  if (xcorr_->search_range()) return xcorr_->search_range();
  std::vector<std::string> ignored;  // the frame's own evaluation warns of them
  return xcorr_->search_range(prepared(measurement, ignored));
}

EvaluationResult DisplacementEvaluator::probe(const cv::Mat& measurement, const std::vector<cv::Point2d>& points) {
  std::vector<std::string> warnings;
  const cv::Mat image = prepared(measurement, warnings);
  if (xcorr_) return warned(std::move(warnings), xcorr_->probe(image, points));
  // Flow is dense anyway: evaluate a grid with step 1 restricted to the
  // points' windows would cost the same; take the nearest grid vector.
  EvaluationResult full = evaluate_flow(reference_, image, options_.flow, mask_);
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
  return warned(std::move(warnings), std::move(result));
}

EvaluationResult evaluate_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                       const EvaluatorOptions& options, const cv::Mat& mask) {
  if (options.preprocess.method != Preprocessing::kNone) {
    return DisplacementEvaluator(reference, options, mask).evaluate(measurement);
  }
  if (options.method == Method::kCrossCorrelation) return evaluate_xcorr(reference, measurement, options.xcorr, mask);
  return evaluate_flow(reference, measurement, options.flow, mask);
}

EvaluationResult probe_displacement(const cv::Mat& reference, const cv::Mat& measurement,
                                    const std::vector<cv::Point2d>& points, const EvaluatorOptions& options,
                                    const cv::Mat& mask) {
  return DisplacementEvaluator(reference, options, mask).probe(measurement, points);
}

}  // namespace bosfuse::fusion
