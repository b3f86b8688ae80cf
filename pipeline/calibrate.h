#pragma once
// calibrate_run: from the probe series a processing stored, each
// thermocouple's rise above the anchor, aligned to the frame times
// (experiment seconds), is fitted against the shift magnitude through the
// origin: T = anchor + slope·|shift|, °C per px of shift for each
// thermocouple position.
//
// The anchor is the temperature where BOS sees no shift. BOS measures the
// change from the reference image, which is by definition the undisturbed
// air: so the anchor is the geometry's ambient_temperature_c (the run's
// [geometry], or --geometry), the same the physics conversion integrates
// from, with its [geometry.uncertainty] σ as the anchor's standard
// uncertainty. The thermocouple's reading at the reference frame is then a
// check only: when it differs from ambient by more than
// ambient_check_sigmas × that σ, the summary and the stored JSON say so
// (the reference image was not taken at ambient, or the thermocouple is not
// where the image is undisturbed), but nothing is refused for it. One rule
// when the geometry states no ambient: the physics conversion then takes
// the thermocouples at the reference frame as the ambient, and so does the
// calibration (each its own reading, σ 0), the room taken as still.
//
// The calibration is stored in the run only when every channel's fit
// passes its checks (fusion/calibration.h: the slope's sign physics
// expects, r², residual, points, the shift range against its uncertainty);
// otherwise it is refused, each problem named with its numbers, and nothing
// is stored — unless `force`, which stores it marked forced, with a warning
// naming what failed. The next process_run converts probe shifts with the
// stored calibration; clear_calibration() ends that (the physical model
// again), keeping the calibrations before it as the run's history.
//
// The reference frame's thermocouple reading (the anchor without an
// ambient, else the check): interpolated between the readings around it
// when the frame lies within the thermocouple's record; else the nearest
// reading when it lies within reference_tolerance_s of the frame (a
// reference frame taken a few ms before the first reading).

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "fusion/calibration.h"

namespace bosfuse::pipeline {

struct CalibrateOptions {
  std::string geometry_file;              // for [alignment] camera_offset_s; default: the run's settings
  std::optional<double> camera_offset_s;  // overrides both, experiment seconds
  double estimate_offset_max_s = 0;       // > 0: estimate the offset within ±this
  fusion::CalibrationChecks checks;
  bool force = false;  // store a calibration that fails its checks, marked forced
  // Experiment seconds; 0: the larger of 2 median sample periods and 0.25 s.
  double reference_tolerance_s = 0;
  // The thermocouple at the reference frame may differ from the ambient
  // anchor by this many of the ambient's σ before the summary says so.
  double ambient_check_sigmas = 3;

  std::string Validate() const;  // empty when valid
};

struct CalibrationOutcome {
  std::string text;  // the report printed to the user
  bool stored = false;
  std::vector<std::string> problems;  // "tc1: the slope ...", each check failed (stored anyway when forced)
};

// Throws std::runtime_error when the run has no probe series (process it
// first) or the options are invalid; a refusal is an outcome, not a throw.
CalibrationOutcome calibrate_run(const std::filesystem::path& run_dir, const CalibrateOptions& options);

// Stores a "cleared" record after the newest calibration, so that the next
// process uses the physical model again; nothing else of the run changes.
// Returns what was done (also when there was nothing to clear).
std::string clear_calibration(const std::filesystem::path& run_dir);

}  // namespace bosfuse::pipeline
