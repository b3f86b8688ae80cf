#pragma once
// calibrate_run: from the probe series a processing stored, each
// thermocouple's rise above its reading at the reference frame, aligned to
// the frame times (experiment seconds), is fitted against the shift
// magnitude through the origin: °C per px of shift for each thermocouple
// position. The calibration is stored in the run only when every channel's
// fit passes its checks (fusion/calibration.h: the slope's sign physics
// expects, r², residual, points, the shift range against its uncertainty);
// otherwise it is refused, each problem named with its numbers, and nothing
// is stored — unless `force`, which stores it marked forced, with a warning
// naming what failed. The next process_run converts probe shifts with the
// stored calibration; clear_calibration() ends that (the physical model
// again), keeping the calibrations before it as the run's history.
//
// The reference frame's thermocouple reading: interpolated between the
// readings around it when the frame lies within the thermocouple's record;
// else the nearest reading when it lies within reference_tolerance_s of the
// frame (a reference frame taken a few ms before the first reading).

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
