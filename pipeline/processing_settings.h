#pragma once
// ProcessingSettings: everything `bosfuse process` needs besides the run
// itself — evaluation method, windows, step, passes, probe mode and context,
// ROI, mask, the optical geometry with its ambient and the camera clock
// offset. A run stores the settings each processing used (as JSON, in its
// `processings` table), so a run is a self-describing record: `process`
// with no flags reuses the run's stored settings, flags override them and
// are stored in turn, and `replay` copies them into the new run.
//
// resolve_settings() is the one place that order is decided:
//   flags  >  the run's stored settings  >  the run's experiment file
//   ([geometry], [alignment])  >  built-in defaults,
// and it says where each part came from.
//
// Without a run (`bosfuse evaluate --sequence`), resolve_runless_settings()
// orders: flags  >  a settings file's [processing] table  >  defaults. The
// table's keys are those the run stores (to_json below), so a run's settings
// and a folder's read the same; docs/CONFIG.md lists them.

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "fusion/displacement_evaluator.h"
#include "pipeline/geometry_config.h"

namespace bosfuse::pipeline {

struct ProcessingSettings {
  bool probes_only = false;
  fusion::EvaluatorOptions evaluator;  // default: cross-correlation, window 16 px, step 8 px, 3 passes
  std::string mask;                    // a file in the run folder, relative to it; empty: none
  GeometryConfig geometry;
  std::string source;  // where they came from, in words

  std::string Validate() const;  // empty when usable
};

// What a user asked for on the command line: unset fields keep the stored
// (or default) value.
struct SettingsOverrides {
  std::optional<bool> probes_only;
  std::optional<std::string> method;          // xcorr or flow
  std::optional<std::string> flow_algorithm;  // dis, farneback or tvl1
  std::optional<int> window_px, step_px, passes, probe_context_nodes;
  std::optional<double> max_shift_px;
  std::optional<bool> adaptive_refinement;
  std::optional<double> adaptive_threshold;
  std::optional<std::string> preprocess;  // a name of fusion/preprocess.h: none, normalize, highpass, minmax, denoise
  std::optional<cv::Rect> roi_px;
  std::optional<std::string> mask;           // relative to the run folder, or absolute (then copied into it)
  std::optional<std::string> geometry_file;  // a TOML file with [geometry] / [alignment]

  bool empty() const;
};

nlohmann::ordered_json to_json(const ProcessingSettings& settings);
// Throws std::runtime_error naming the key on a document of another layout.
ProcessingSettings settings_from_json(const nlohmann::json& j);

// The settings a processing of `run_dir` uses: its stored ones (the newest
// complete or inherited processing) with `overrides` applied, else the run's
// experiment file and defaults with `overrides` applied. A mask given as an
// absolute path outside the run folder is copied into it (as masks/NAME), so
// the run keeps every file its settings name.
ProcessingSettings resolve_settings(const std::filesystem::path& run_dir, const SettingsOverrides& overrides);

// The [processing] table of a TOML document (`source_name` names it in
// messages): mode ("full" or "probes"), method, flow_algorithm, window_px,
// step_px, passes, max_shift_px, probe_context_nodes, preprocess, roi_px =
// [x, y, width, height] and mask, as overrides of the defaults; nullopt when the document
// has no such table. A wrong type, value or unknown key is an
// acquisition::ConfigError naming the file, the line and the key. A relative
// mask is returned as written: the caller knows what it is relative to.
std::optional<SettingsOverrides> parse_processing_table(const std::string& text, const std::string& source_name);

// The defaults' evaluator with the evaluator's part of `overrides` applied
// (not their mask, geometry or probe mode), unchecked: what an evaluation
// of one image pair uses, which checks the options itself.
fusion::EvaluatorOptions default_evaluator_with(const SettingsOverrides& overrides);

// The settings of an evaluation without a run: defaults, then the
// [processing] table of `settings_file` when one is given (a relative mask
// there is relative to the file's folder), then `flags` (a mask as given).
// The geometry stays the defaults' and unnamed (displacements only); a flag
// naming a geometry file is refused. Throws when the result is not usable.
ProcessingSettings resolve_runless_settings(const std::string& settings_file, const SettingsOverrides& flags);

// The settings in words, e.g. "full fields, cross-correlation, window 16 px,
// step 8 px, 3 passes, mask holder-mask.png, geometry from run config"
// (without the geometry when it has no source: run-less settings).
std::string describe(const ProcessingSettings& settings);

// The image scale at the flow plane, px per mm: from the run's stored
// settings, else its experiment file's [geometry]; nothing when neither
// gives a geometry (maps and grids are then in px).
std::optional<double> stored_px_per_mm(const std::filesystem::path& run_dir);

// Copies the newest stored settings of `from_run` (and the mask file they
// name) into `to_run` as inherited settings; `replay` uses it. Returns
// whether there were any.
bool inherit_settings(const std::filesystem::path& from_run, const std::filesystem::path& to_run);

}  // namespace bosfuse::pipeline
