#pragma once
// What evaluate() and Evaluator() were asked for: the keyword options named
// as `bosfuse evaluate`'s (window, step, passes, max_shift, method, flow,
// adaptive_refinement, adaptive_threshold, preprocess, roi, mask,
// first_window, dis_preset, subpixel, interpolator) and `settings`, a dict
// of the same options or the path of a TOML file whose [processing] table
// sets them (as `evaluate --settings`); options given override it. They map
// onto the same pipeline::SettingsOverrides and EvaluationChoices the CLI
// fills, and the options are checked by the same Validate(): a bad value is
// a ValueError with its message, an unknown option a TypeError.

#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <vector>

#include "fusion/displacement_evaluator.h"

namespace bosfuse::python {

struct EvaluationRequest {
  fusion::EvaluatorOptions options;
  cv::Mat mask;                 // a mask given as an array (empty: none, or a file's)
  std::string mask_path;        // a mask given as a file (empty: none)
  pybind11::object mask_array;  // the NumPy array `mask` shares pixels with, kept alive

  // The mask's pixels (empty: none), the file read now: call it with the GIL released.
  cv::Mat read_mask() const;
};

EvaluationRequest evaluation_request(const pybind11::dict& kwargs);

// `probes` as points, each checked to lie on an image of `size` (a
// ValueError otherwise). Pure C++: call it with the GIL released.
std::vector<cv::Point2d> probe_points(const std::vector<std::pair<double, double>>& probes, cv::Size size);

}  // namespace bosfuse::python
