// bosfuse.quality(): the image quality index of a captured background
// against the digital pattern it was printed from, and the verdict, as
// `bosfuse quality IMAGE --reference PATTERN` gives them (the keys of its
// --json, fusion/image_quality.h and fusion/scene_match.h).
#include <pybind11/stl.h>

#include "fusion/image_quality.h"
#include "fusion/scene_match.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "python/json.h"
#include "pipeline/quality_json.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

const char* kQualityDoc = R"(quality(image, reference, *, window=8) -> dict

The image quality index of a captured background `image` against the pattern
`reference` it was printed from, as `bosfuse quality IMAGE --reference REF --json -`
gives it: q_l, q_c, q_mod, the images' means and standard deviations (of full
scale), the verdict ('good', 'usable', 'poor', 'not the same scene', 'no
texture') with scene_correlation, scene_tiles and scene_thresholds,
universal_index (the Wang-Bovik Q over window x window px), mean_local_q_mod,
window_px; and beyond the JSON: reason, the verdict line the command prints,
warnings (colour converted, reference resized) and local_q_mod, the map of the
local Q_mod (float64, one value per window position). Images as evaluate's
(arrays or paths).)";

py::dict quality(const py::object& image, const py::object& reference, int window) {
  const ImageInput captured_input(image, "image"), pattern_input(reference, "reference");
  fusion::QualityOptions options;
  options.window_px = window;
  if (const auto problem = options.Validate(); !problem.empty()) throw py::value_error("window: " + problem);
  fusion::QualityReport report;
  fusion::SceneMatch scene;
  {
    py::gil_scoped_release release;
    const cv::Mat captured = captured_input.read(), pattern = pattern_input.read();
    report = fusion::assess_quality(captured, pattern, options);
    scene = fusion::match_scene(captured, pattern);
  }
  nlohmann::ordered_json j = pipeline::to_json(report.global);
  j.update(pipeline::to_json(scene));
  j["universal_index"] = report.universal_index;
  j["mean_local_q_mod"] = report.mean_local_q_mod;
  j["window_px"] = window;
  py::dict out = to_python(j);
  out["reason"] = scene.Describe();
  std::vector<std::string> warnings = report.warnings;
  warnings.insert(warnings.end(), scene.warnings.begin(), scene.warnings.end());
  out["warnings"] = py::cast(warnings);
  out["local_q_mod"] = mat_array(report.local_q_mod);
  return out;
}

}  // namespace

void bind_quality(py::module_& m) {
  m.def("quality", &quality, kQualityDoc, py::arg("image"), py::arg("reference"), py::kw_only(), py::arg("window") = 8);
}

}  // namespace bosfuse::python
