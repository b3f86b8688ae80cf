#pragma once
// What `bosfuse process` and `bosfuse calibrate` do to a run, as functions
// the command files call (and tests can reason about):
//
// process_run: every non-reference frame is evaluated against the run's
// reference frame (the first with is_reference = 1) — the full displacement
// field, or only windows at the thermocouples' image positions
// (probes_only). Full fields are written under RUN/fields/ as CSV together
// with the temperature field of the physical model (bos_geometry.h,
// temperature_field.h). Probe temperatures come from the run's newest
// calibration when there is one, else from the model's field (full mode),
// else they stay empty and the probe's Newton fit is made on its shift. Each
// thermocouple and each probe series gets a Newton fit (t = 0 at the first
// evaluated frame; thermocouple samples within the frames' span; probe times
// moved onto the host clock by the camera offset of the calibration, else of
// [alignment]), each thermocouple–probe pair an agreement. Everything replaces the run's earlier
// results in one transaction.
//
// calibrate_run: from the stored probe series (process first), the
// thermocouple's rise above its reading at the reference frame, aligned to
// the frame times, is fitted against the shift magnitude through the origin:
// °C per px of shift for each thermocouple position.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "app/geometry_config.h"
#include "fusion/displacement_evaluator.h"

namespace bosfuse::app {

struct ProcessOptions {
  bool probes_only = false;
  // xcorr.probe_context_nodes: 1 (fast, within ~0.01-0.02 px of the full field)
  // or -1 (exact: equal to the full field, ~40x slower per probe).
  fusion::EvaluatorOptions evaluator;
  std::string geometry_file;  // empty: the run's config, else defaults
  std::string mask_file;      // non-zero pixels are not evaluated; relative to the run folder unless absolute
  std::function<void(const std::string&)> progress;  // one line per step; may be empty
};

struct ProcessReport {
  std::size_t frames = 0;
  std::size_t probes = 0;
  std::size_t fits_ok = 0;
  std::size_t fits = 0;
  std::size_t agreements = 0;
  std::string temperature_source;  // calibration, physical model, none
  double seconds = 0;
  std::string text;  // what a person reads at the end
};

ProcessReport process_run(const std::filesystem::path& run_dir, const ProcessOptions& options);

struct CalibrateOptions {
  std::string geometry_file;              // for [alignment] camera_offset_s
  std::optional<double> camera_offset_s;  // overrides the file
  double estimate_offset_max_s = 0;       // > 0: estimate the offset within ±this
};

// Returns the report printed to the user; throws when nothing could be
// calibrated.
std::string calibrate_run(const std::filesystem::path& run_dir, const CalibrateOptions& options);

}  // namespace bosfuse::app
