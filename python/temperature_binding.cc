// bosfuse.temperature_field(): the temperature behind a displacement field,
// solved as `bosfuse process` solves each frame's full field
// (fusion/temperature_field.h) with the geometry of an experiment file's
// [geometry] table (pipeline/geometry_config.h): given as a dict under the
// file's names, or as the file's path. The dict is checked by the same
// reader as the file, so a bad key or value is the ConfigError the command
// would give, naming the key.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "fusion/temperature_field.h"
#include "pipeline/geometry_config.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "python/field.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

const char* kTemperatureDoc = R"(temperature_field(field, geometry=None, *, uncertainty=False, samples=64, seed=29) -> types.SimpleNamespace

The temperature field behind a displacement Field, as `bosfuse process` solves a
frame's full field. geometry: a dict with the names of an experiment file's
[geometry] table (wavelength_nm, ambient_pressure_pa, ambient_temperature_c, z_d_m,
depth_m, magnification, pixel_pitch_um, px_per_mm_flow, open_edges=['top', ...]),
the path of a TOML file holding that table (as `process --geometry`), or None for
the defaults. uncertainty: also estimate each node's random standard uncertainty
of T from the field's sigma_u, sigma_v by `samples` noise draws (seeded).
Returns arrays shaped as the field's (ny, nx): x, y (px), temperature_c (NaN where
not physical), sigma_c (NaN where not estimated, measured or physical),
refractive_index, sigma_refractive_index, measured and physical (bool); and summary
(the solve's one-line report) and geometry (the set-up's).)";

// A Python value as TOML text: TOML's strings, numbers and arrays are JSON's.
std::string toml_value(const py::handle& value, const std::string& key) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(value)) return std::to_string(value.cast<long long>());
  if (py::isinstance<py::float_>(value)) return nlohmann::json(value.cast<double>()).dump();
  if (py::isinstance<py::str>(value)) return nlohmann::json(value.cast<std::string>()).dump();
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text = "[";
    for (const auto& item : value) text += (text.size() > 1 ? ", " : "") + toml_value(item, key);
    return text + "]";
  }
  throw py::type_error(fmt::format("geometry: {} must be a number, a string or a list, not {}", key,
                                   py::str(value.get_type().attr("__name__")).cast<std::string>()));
}

// The dict as the [geometry] table (and [geometry.NAME] for a dict in it).
std::string geometry_toml(const py::dict& geometry) {
  std::string text = "[geometry]\n", tables;
  for (const auto& [key, value] : geometry) {
    const auto name = py::str(key).cast<std::string>();
    if (!py::isinstance<py::dict>(value)) {
      text += fmt::format("{} = {}\n", name, toml_value(value, name));
      continue;
    }
    tables += fmt::format("[geometry.{}]\n", name);
    for (const auto& [k, v] : value.cast<py::dict>()) {
      const auto sub = name + "." + py::str(k).cast<std::string>();
      tables += fmt::format("{} = {}\n", py::str(k).cast<std::string>(), toml_value(v, sub));
    }
  }
  return text + tables;
}

pipeline::GeometryConfig geometry_config(const py::object& geometry) {
  if (geometry.is_none()) return pipeline::resolve_geometry_config("", "");
  if (const auto path = path_argument(geometry)) return pipeline::resolve_geometry_config(*path, "");
  if (!py::isinstance<py::dict>(geometry)) {
    throw py::type_error("geometry: expected a dict of the [geometry] table's keys, a TOML file's path or None");
  }
  return *pipeline::parse_geometry_config(geometry_toml(geometry.cast<py::dict>()), "geometry");
}

py::object temperature_field(const Field& field, const py::object& geometry, bool uncertainty, int samples,
                             std::uint64_t seed) {
  pipeline::GeometryConfig config = geometry_config(geometry);
  config.temperature_field.estimate_uncertainty = uncertainty;
  config.temperature_field.uncertainty_samples = samples;
  config.temperature_field.uncertainty_seed = seed;
  if (const auto problem = config.temperature_field.Validate(); !problem.empty()) throw py::value_error(problem);
  const fusion::DisplacementField displacement = field.to_displacement();
  const fusion::BosGeometry optics(config.geometry);
  fusion::TemperatureFieldResult result;
  {
    py::gil_scoped_release release;
    result = fusion::recover_temperature_field(displacement, optics, config.temperature_field);
  }
  const fusion::TemperatureField& t = result.field;
  const auto node = [&](const std::vector<double>& values) {
    return grid_array<double>(t.rows, t.cols, [&](std::size_t i) { return values[i]; });
  };
  const auto flags = [&](const std::vector<std::uint8_t>& values) {
    return grid_array<bool>(t.rows, t.cols, [&](std::size_t i) { return values[i] != 0; });
  };
  py::dict out(py::arg("x") = grid_array<double>(t.rows, t.cols, [&](std::size_t i) { return t.x0_px + t.step_px * (i % t.cols); }),
               py::arg("y") = grid_array<double>(t.rows, t.cols, [&](std::size_t i) { return t.y0_px + t.step_px * (i / t.cols); }),
               py::arg("temperature_c") = node(t.temperature_c), py::arg("sigma_c") = node(t.sigma_c),
               py::arg("refractive_index") = node(t.refractive_index),
               py::arg("sigma_refractive_index") = node(t.sigma_refractive_index),
               py::arg("measured") = flags(t.measured), py::arg("physical") = flags(t.physical),
               py::arg("summary") = result.summary.brief_report(), py::arg("geometry") = optics.brief_report());
  return py::module_::import("types").attr("SimpleNamespace")(**out);
}

}  // namespace

void bind_temperature(py::module_& m) {
  m.def("temperature_field", &temperature_field, kTemperatureDoc, py::arg("field"), py::arg("geometry") = py::none(),
        py::kw_only(), py::arg("uncertainty") = false, py::arg("samples") = 64, py::arg("seed") = 29);
}

}  // namespace bosfuse::python
