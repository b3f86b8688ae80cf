// bosfuse.background(): the random-dot BOS background pattern
// `bosfuse background` writes (sim/background_pattern.h), as a NumPy
// array, under the command's option names; `out` also writes the file as
// the command does (PNG or TIFF carrying the dpi).
#include <pybind11/stl.h>

#include <optional>

#include "python/arrays.h"
#include "python/bindings.h"
#include "sim/background_pattern.h"
#include "storage/output_path.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

const char* kBackgroundDoc = R"(background(*, width=1024, height=768, dot_px=3, dot_mm=None, dpi=300, coverage=0.5, grey_levels=(0, 43, 86, 128), seed=1, out=None) -> numpy.ndarray

The printable random-dot pattern of `bosfuse background`, its options under the
same names (--dot-px is dot_px, --grey-levels grey_levels): a uint8 array
(height, width), dots of the grey levels on white. dot_mm (with dpi) replaces
dot_px. The same seed gives the same pattern as the command. out: also write it
there (.png or .tif, with the dpi for printing), as `background -o OUT` does.)";

py::array background(int width, int height, double dot_px, std::optional<double> dot_mm, double dpi, double coverage,
                     const std::vector<int>& grey_levels, std::uint64_t seed, const py::object& out) {
  sim::PatternOptions options;
  options.width_px = width;
  options.height_px = height;
  options.dot_diameter_px = dot_px;
  options.dot_diameter_mm = dot_mm.value_or(0);
  options.dpi = dpi;
  options.coverage = coverage;
  options.grey_levels = grey_levels;
  options.seed = seed;
  if (const auto problem = options.Validate(); !problem.empty()) throw py::value_error(problem);
  const std::optional<std::string> path = out.is_none() ? std::nullopt : path_argument(out);
  if (!out.is_none() && !path) throw py::type_error("out: expected a path (str or os.PathLike)");
  if (path) storage::check_output_path(*path, "out");  // never one of a run's own files, as the command
  cv::Mat image;
  {
    py::gil_scoped_release release;
    image = sim::render_pattern(sim::generate_pattern(options));
    if (path) sim::write_pattern_image(*path, image, options.dpi);
  }
  return mat_array(image);
}

}  // namespace

void bind_background(py::module_& m) {
  const sim::PatternOptions d;
  m.def("background", &background, kBackgroundDoc, py::kw_only(), py::arg("width") = d.width_px,
        py::arg("height") = d.height_px, py::arg("dot_px") = d.dot_diameter_px, py::arg("dot_mm") = py::none(),
        py::arg("dpi") = d.dpi, py::arg("coverage") = d.coverage, py::arg("grey_levels") = d.grey_levels,
        py::arg("seed") = d.seed, py::arg("out") = py::none());
}

}  // namespace bosfuse::python
