#include "pipeline/evaluation_choices.h"

#include <map>
#include <stdexcept>

#include "fusion/optical_flow.h"

namespace bosfuse::pipeline {
namespace {

const std::map<std::string, fusion::Interpolator>& interpolators() {
  static const std::map<std::string, fusion::Interpolator> names{{"cubic", fusion::Interpolator::kCubic},
                                                                 {"lanczos3", fusion::Interpolator::kLanczos3},
                                                                 {"lanczos4", fusion::Interpolator::kLanczos4},
                                                                 {"bspline3", fusion::Interpolator::kBSpline3},
                                                                 {"bspline5", fusion::Interpolator::kBSpline5}};
  return names;
}

}  // namespace

std::string EvaluationChoices::Validate() const {
  if (first_window_px < 0) return "first window must be at least 0 px (0: the evaluator's choice)";
  if (subpixel != "auto" && subpixel != "gauss2d" && subpixel != "gauss3") {
    return "subpixel '" + subpixel + "' must be one of auto, gauss2d, gauss3";
  }
  if (!interpolators().contains(interpolator)) {
    return "interpolator '" + interpolator + "' must be one of bspline5, bspline3, lanczos3, lanczos4, cubic";
  }
  if (!fusion::parse_dis_preset(dis_preset)) return "DIS preset '" + dis_preset + "' must be one of medium, fast, ultrafast";
  return {};
}

void apply_evaluation_choices(const EvaluationChoices& choices, fusion::EvaluatorOptions& options) {
  if (const auto problem = choices.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  options.xcorr.first_window_px = choices.first_window_px;
  // "auto": the 2-D fit where peaks lock (first pass), 3-point after deformation.
  if (choices.subpixel == "gauss3") {
    options.xcorr.subpixel = options.xcorr.refinement_subpixel = fusion::SubpixelEstimator::kGaussian3Point;
  } else if (choices.subpixel == "gauss2d") {
    options.xcorr.subpixel = options.xcorr.refinement_subpixel = fusion::SubpixelEstimator::kGaussian2dFit;
  }
  options.xcorr.interpolator = interpolators().at(choices.interpolator);
  options.flow.dis_preset = fusion::parse_dis_preset(choices.dis_preset).value();
}

}  // namespace bosfuse::pipeline
