#pragma once
// EvaluationChoices: the evaluator's choices a run's stored settings have no
// key for — the first pass's window, the subpixel peak estimator, the
// deformation interpolator and the DIS preset of optical flow — by the
// names `bosfuse evaluate` takes them (--first-window, --subpixel,
// --interpolator, --dis-preset) and the Python module's evaluate() too, so
// both map a name to the same option.

#include <string>

#include "fusion/displacement_evaluator.h"

namespace bosfuse::pipeline {

struct EvaluationChoices {
  int first_window_px = 0;            // 0: the evaluator's own choice
  std::string dis_preset = "medium";  // medium, fast or ultrafast
  std::string subpixel = "auto";      // auto (2-D fit, then 3-point after deformation), gauss2d or gauss3
  std::string interpolator = "bspline5";  // bspline5, bspline3, lanczos3, lanczos4 or cubic

  std::string Validate() const;  // empty when usable, else which choice is unknown and what is allowed
};

// The choices applied to `options`; throws std::invalid_argument with
// Validate()'s reason when they are not usable.
void apply_evaluation_choices(const EvaluationChoices& choices, fusion::EvaluatorOptions& options);

}  // namespace bosfuse::pipeline
