#pragma once
// The `[geometry]` and `[alignment]` tables of a TOML file (docs/CONFIG.md,
// example examples/geometry.toml): the optical set-up that turns
// displacements into temperatures, and the camera–host clock offset. Read
// from a file given with --geometry, else from the run's stored experiment
// file, else defaults (said so, since temperatures from a default geometry
// are only illustrative). Errors name the file, line and key.

#include <optional>
#include <string>

#include "fusion/bos_geometry.h"
#include "fusion/temperature_budget.h"
#include "fusion/temperature_field.h"

namespace bosfuse::pipeline {

struct GeometryConfig {
  fusion::BosGeometryOptions geometry;
  fusion::TemperatureFieldOptions temperature_field;  // open_edges: where the flow leaves the image
  fusion::TypeBUncertainties uncertainty;             // [geometry.uncertainty]: the set-up's, for the budget
  bool ambient_given = false;                         // ambient_temperature_c was in the file
  double camera_offset_s = 0;                         // frame stamped t happened at host time t + offset
  std::string source;                                 // where it came from: a path, "run config" or "defaults"
};

// `text` is a whole TOML document; nullopt when it has neither table.
std::optional<GeometryConfig> parse_geometry_config(const std::string& text, const std::string& source_name);

// --geometry FILE when given, else the run's config, else defaults.
GeometryConfig resolve_geometry_config(const std::string& geometry_file, const std::string& run_config_toml);

}  // namespace bosfuse::pipeline
