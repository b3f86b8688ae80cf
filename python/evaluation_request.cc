#include "python/evaluation_request.h"

#include <fmt/format.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <string_view>

#include "pipeline/evaluation_choices.h"
#include "pipeline/image_io.h"
#include "pipeline/processing_settings.h"
#include "python/arrays.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

// A constant table, not a function-local static: nothing here is
// initialised on first use, where two threads could meet.
constexpr std::string_view kOptionNames[] = {"window",       "step",       "passes",          "max_shift",
                                             "method",       "flow",       "adaptive_refinement",
                                             "adaptive_threshold",         "preprocess",      "roi",
                                             "mask",         "first_window", "dis_preset",    "subpixel",
                                             "interpolator"};

bool known_option(std::string_view name) {
  return std::find(std::begin(kOptionNames), std::end(kOptionNames), name) != std::end(kOptionNames);
}

template <typename T>
void take(const py::dict& o, const char* name, std::optional<T>& to) {
  if (o.contains(name) && !o[name].is_none()) to = o[name].cast<T>();
}

pipeline::SettingsOverrides overrides_from(const py::dict& o) {
  pipeline::SettingsOverrides s;
  take(o, "method", s.method);
  take(o, "flow", s.flow_algorithm);
  take(o, "window", s.window_px);
  take(o, "step", s.step_px);
  take(o, "passes", s.passes);
  take(o, "max_shift", s.max_shift_px);
  take(o, "adaptive_threshold", s.adaptive_threshold);
  take(o, "preprocess", s.preprocess);
  if (o.contains("adaptive_refinement") && !o["adaptive_refinement"].is_none()) {
    const py::object a = o["adaptive_refinement"];
    s.adaptive_refinement = py::isinstance<py::str>(a) ? a.cast<std::string>() == "on" : a.cast<bool>();
  }
  if (o.contains("roi") && !o["roi"].is_none()) {
    const auto r = o["roi"].cast<std::vector<int>>();
    if (r.size() != 4) throw py::value_error("roi: expected (x, y, width, height) in pixels");
    if (r[0] < 0 || r[1] < 0 || r[2] <= 0 || r[3] <= 0) {
      throw py::value_error("roi: x and y must be at least 0, width and height at least 1");
    }
    s.roi_px = cv::Rect(r[0], r[1], r[2], r[3]);
  }
  if (o.contains("mask") && !o["mask"].is_none()) s.mask = path_argument(o["mask"]);
  return s;
}

pipeline::EvaluationChoices choices_from(const py::dict& o) {
  pipeline::EvaluationChoices c;
  if (o.contains("first_window")) c.first_window_px = o["first_window"].cast<int>();
  if (o.contains("dis_preset")) c.dis_preset = o["dis_preset"].cast<std::string>();
  if (o.contains("subpixel")) c.subpixel = o["subpixel"].cast<std::string>();
  if (o.contains("interpolator")) c.interpolator = o["interpolator"].cast<std::string>();
  if (const auto problem = c.Validate(); !problem.empty()) throw py::value_error(problem);
  return c;
}

// The options of `settings` (a dict) under those of `kwargs`; `file` gets
// the path when `settings` is one.
py::dict merged_options(const py::dict& kwargs, std::string& file) {
  py::dict options;
  if (kwargs.contains("settings") && !kwargs["settings"].is_none()) {
    const py::object settings = kwargs["settings"];
    if (auto path = path_argument(settings)) {
      file = *path;
    } else if (py::isinstance<py::dict>(settings)) {
      for (auto item : settings.cast<py::dict>()) options[item.first] = item.second;
    } else {
      throw py::type_error("settings: expected a dict of options or the path of a TOML file");
    }
  }
  for (auto item : kwargs) {
    if (item.first.cast<std::string>() != "settings") options[item.first] = item.second;
  }
  for (auto item : options) {
    const auto name = item.first.cast<std::string>();
    if (!known_option(name)) {
      std::string known;
      for (const auto n : kOptionNames) known += (known.empty() ? "" : ", ") + std::string(n);
      throw py::type_error(fmt::format("unknown option '{}'; the options are {}, settings", name, known));
    }
  }
  return options;
}

}  // namespace

EvaluationRequest evaluation_request(const py::dict& kwargs) {
  std::string settings_file;
  const py::dict o = merged_options(kwargs, settings_file);
  const pipeline::SettingsOverrides overrides = overrides_from(o);
  EvaluationRequest request;
  std::string mask_path = overrides.mask.value_or("");
  if (settings_file.empty()) {
    request.options = pipeline::default_evaluator_with(overrides);
  } else {
    const auto settings = pipeline::resolve_runless_settings(settings_file, overrides);
    request.options = settings.evaluator;
    mask_path = settings.mask;
  }
  pipeline::apply_evaluation_choices(choices_from(o), request.options);
  if (const auto problem = request.options.Validate(); !problem.empty()) throw py::value_error(problem);
  if (o.contains("mask") && py::isinstance<py::array>(o["mask"])) {
    request.mask_array = o["mask"];
    request.mask = image_argument(request.mask_array, "mask");
  } else {
    request.mask_path = mask_path;
  }
  return request;
}

cv::Mat EvaluationRequest::read_mask() const {
  return mask_path.empty() ? mask : pipeline::read_image(mask_path, "mask");
}

std::vector<cv::Point2d> probe_points(const std::vector<std::pair<double, double>>& probes, cv::Size size) {
  std::vector<cv::Point2d> points;
  for (const auto& p : probes) {
    if (!(p.first >= 0 && p.second >= 0 && p.first <= size.width - 1 && p.second <= size.height - 1)) {
      throw py::value_error(fmt::format("probe ({}, {}) lies outside the {}x{} image", p.first, p.second, size.width,
                                        size.height));
    }
    points.emplace_back(p.first, p.second);
  }
  return points;
}

}  // namespace bosfuse::python
