#pragma once
// calibrate_run: from the probe series a processing stored, each
// thermocouple's rise above its reading at the reference frame, aligned to
// the frame times (experiment seconds), is fitted against the shift
// magnitude through the origin: °C per px of shift for each thermocouple
// position. The calibration is stored in the run; the next process_run
// converts probe shifts with it.

#include <filesystem>
#include <optional>
#include <string>

namespace bosfuse::pipeline {

struct CalibrateOptions {
  std::string geometry_file;              // for [alignment] camera_offset_s; default: the run's settings
  std::optional<double> camera_offset_s;  // overrides both, experiment seconds
  double estimate_offset_max_s = 0;       // > 0: estimate the offset within ±this
};

// Returns the report printed to the user; throws when nothing could be
// calibrated.
std::string calibrate_run(const std::filesystem::path& run_dir, const CalibrateOptions& options);

}  // namespace bosfuse::pipeline
