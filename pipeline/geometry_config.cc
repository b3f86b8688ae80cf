#include "pipeline/geometry_config.h"

#include <fstream>
#include <sstream>

#include "acquisition/config/toml_reader.h"

namespace bosfuse::pipeline {
namespace {

using acquisition::TomlReader;

// open_edges = ["top"]: image edges the heated air leaves through.
void read_open_edges(const TomlReader& r, fusion::TemperatureFieldOptions& field) {
  const toml::node* node = r.node("open_edges");
  if (!node) return;
  const toml::array* edges = node->as_array();
  if (!edges) r.fail("open_edges", "expected an array of \"top\", \"bottom\", \"left\", \"right\"");
  for (const auto& edge : *edges) {
    const auto name = edge.value<std::string>().value_or("");
    bool* flag = name == "top"      ? &field.open_top
                 : name == "bottom" ? &field.open_bottom
                 : name == "left"   ? &field.open_left
                 : name == "right"  ? &field.open_right
                                    : nullptr;
    if (!flag) r.fail("open_edges", "expected \"top\", \"bottom\", \"left\" or \"right\", not \"" + name + "\"");
    *flag = true;
  }
  if (const auto problem = field.Validate(); !problem.empty()) r.fail("open_edges", problem);
}

// [geometry.uncertainty]: the set-up's standard uncertainties (temperature_budget.h).
void read_uncertainty(const TomlReader& r, fusion::TypeBUncertainties& u) {
  constexpr double kLargest = 1e9;
  u.gladstone_dale_relative = r.number_in("gladstone_dale_relative", u.gladstone_dale_relative, 0, 1,
                                          "a relative standard uncertainty");
  u.ambient_pressure_pa = r.number_in("ambient_pressure_pa", u.ambient_pressure_pa, 0, kLargest, "Pa");
  u.ambient_temperature_c = r.number_in("ambient_temperature_c", u.ambient_temperature_c, 0, kLargest, "°C");
  u.z_d_relative = r.number_in("z_d_relative", u.z_d_relative, 0, 1, "a relative standard uncertainty");
  u.magnification_relative =
      r.number_in("magnification_relative", u.magnification_relative, 0, 1, "a relative standard uncertainty");
  u.depth_relative = r.number_in("depth_relative", u.depth_relative, 0, 1, "a relative standard uncertainty");
  r.reject_unknown_keys();
}

void read_geometry(const TomlReader& r, GeometryConfig& config) {
  auto& g = config.geometry;
  g.wavelength_nm = r.optional_number("wavelength_nm").value_or(g.wavelength_nm);
  g.ambient_pressure_pa = r.optional_number("ambient_pressure_pa").value_or(g.ambient_pressure_pa);
  if (const auto ambient = r.optional_number("ambient_temperature_c")) {
    g.ambient_temperature_c = *ambient;
    config.ambient_given = true;
  }
  g.z_d_m = r.optional_number("z_d_m").value_or(g.z_d_m);
  g.depth_m = r.optional_number("depth_m").value_or(g.depth_m);
  g.magnification = r.optional_number("magnification").value_or(g.magnification);
  g.pixel_pitch_um = r.optional_number("pixel_pitch_um").value_or(g.pixel_pitch_um);
  g.px_per_mm_flow = r.optional_number("px_per_mm_flow").value_or(g.px_per_mm_flow);
  read_open_edges(r, config.temperature_field);
  if (const auto uncertainty = r.table("uncertainty")) read_uncertainty(*uncertainty, config.uncertainty);
  r.reject_unknown_keys();
  if (const auto problem = g.Validate(); !problem.empty()) r.fail("", problem);
}

}  // namespace

std::optional<GeometryConfig> parse_geometry_config(const std::string& text, const std::string& source_name) {
  const toml::table root = acquisition::parse_toml(text, source_name);
  const TomlReader reader(root, "", source_name);
  const auto geometry = reader.table("geometry");
  const auto alignment = reader.table("alignment");
  if (!geometry && !alignment) return std::nullopt;
  GeometryConfig config;
  config.source = source_name;
  if (geometry) read_geometry(*geometry, config);
  if (alignment) {
    config.camera_offset_s = alignment->optional_number("camera_offset_s").value_or(0.0);
    alignment->reject_unknown_keys();
  }
  return config;
}

GeometryConfig resolve_geometry_config(const std::string& geometry_file, const std::string& run_config_toml) {
  if (!geometry_file.empty()) {
    std::ifstream in(geometry_file);
    if (!in) throw std::runtime_error("cannot read geometry file '" + geometry_file + "'");
    std::ostringstream text;
    text << in.rdbuf();
    if (auto config = parse_geometry_config(text.str(), geometry_file)) return *config;
    throw std::runtime_error(geometry_file + ": no [geometry] or [alignment] table");
  }
  // The run's experiment file is not required to parse as a geometry file:
  // only its two tables are read, and a problem there is reported.
  if (!run_config_toml.empty()) {
    try {
      if (auto config = parse_geometry_config(run_config_toml, "run config")) return *config;
    } catch (const acquisition::ConfigError&) {
      if (run_config_toml.find("[geometry]") != std::string::npos) throw;
    }
  }
  GeometryConfig defaults;
  defaults.source = "defaults";
  return defaults;
}

}  // namespace bosfuse::pipeline
