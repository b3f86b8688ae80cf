// bosfuse calibrate: fits each thermocouple's rise above the ambient (the
// reference image's undisturbed air) against the BOS shift at its image
// position (°C per px of shift, through the origin, with standard
// uncertainty) and stores it in the run when it passes its checks; a later
// `bosfuse process` converts probe shifts with it. A refused calibration
// exits kExitRefused with its problems; --force stores it with a warning;
// --clear removes it.

#include <spdlog/spdlog.h>

#include <iostream>

#include "app/command.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "pipeline/calibrate.h"

namespace bosfuse::app {
namespace {

struct CalibrateArgs {
  std::string run;
  std::string geometry;
  std::optional<double> camera_offset_s;
  double estimate_offset_s = 0;
  bool force = false;
  bool clear = false;
  std::string flow = "heated";
  pipeline::CalibrateOptions options;
};

void add_checks(CLI::App* cmd, CalibrateArgs& args) {
  auto& c = args.options.checks;
  cmd->add_option("--min-points", c.min_points, "Fewest frames a thermocouple's fit needs")
      ->check(CLI::Range(std::size_t{2}, std::size_t{1000000}))
      ->capture_default_str();
  cmd->add_option("--min-r2", c.min_r2, "Least r2 of a fit (1 - SSR/SST about the mean rise)")
      ->check(CLI::Range(-1e9, 1.0))
      ->capture_default_str();
  cmd->add_option("--max-residual", c.max_residual_rms_c, "Largest residual RMS of a fit, degC")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--min-shift-range", c.min_shift_range_sigmas,
                  "Least shift range at a thermocouple, in multiples of the shift's uncertainty")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--shift-noise", c.shift_noise_floor_px,
                  "The shift's uncertainty, px, when the probe samples carry none")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--flow", args.flow,
                  "heated: the flow is hotter than the reference's air (slope > 0); cooled: colder (slope < 0)")
      ->check(CLI::IsMember({"heated", "cooled"}))
      ->capture_default_str();
  cmd->add_option("--reference-tolerance", args.options.reference_tolerance_s,
                  "Seconds from the reference frame within which the nearest reading stands for it when the frame "
                  "lies outside the thermocouple's record (0: the larger of 2 sample periods and 0.25 s)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

void run_calibrate(CalibrateArgs& args) {
  if (args.clear) {
    std::cerr << pipeline::clear_calibration(args.run);
    return;
  }
  auto& options = args.options;
  options.geometry_file = args.geometry;
  options.camera_offset_s = args.camera_offset_s;
  options.estimate_offset_max_s = args.estimate_offset_s;
  options.force = args.force;
  options.checks.expected_sign = args.flow == "cooled" ? -1 : +1;
  const auto outcome = pipeline::calibrate_run(args.run, options);
  std::cerr << outcome.text;  // a summary for a person: standard output holds data only
  if (!outcome.stored) {
    std::string problems;
    for (const auto& p : outcome.problems) problems += "\n  " + p;
    throw CommandFailure(kExitRefused, "calibration refused, nothing stored:" + problems);
  }
  if (!outcome.problems.empty()) {
    std::string problems;
    for (const auto& p : outcome.problems) problems += "\n  " + p;
    spdlog::warn("stored a FORCED calibration that failed its checks:{}", problems);
  }
}

void add_calibrate(CLI::App& root) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = root.add_subcommand(
      "calibrate", "Fit °C per px of shift at each thermocouple from a processed run and store it in the run");
  cmd->add_option("run", args->run, "Run folder (processed: `bosfuse process RUN --mode probes` is enough)")
      ->required()
      ->transform(run_folder_argument());
  cmd->add_option("--geometry", args->geometry, "TOML file whose [alignment] camera_offset_s is used");
  cmd->add_option("--camera-offset", args->camera_offset_s,
                  "Camera clock offset, experiment s: a frame stamped t happened at t + offset");
  cmd->add_option("--estimate-offset", args->estimate_offset_s,
                  "Estimate the camera clock offset within +-this many seconds (needs a feature in the record; the "
                  "answer must be the same over 3 times the window)");
  cmd->add_flag("--force", args->force, "Store the calibration even when it fails its checks (with a warning)");
  auto* clear =
      cmd->add_flag("--clear", args->clear,
                    "Remove the run's calibration (kept as history): `process` uses the physical model again");
  add_checks(cmd, *args);
  for (const char* other : {"--force", "--camera-offset", "--estimate-offset", "--geometry"}) {
    clear->excludes(cmd->get_option(other));
  }
  cmd->callback([args] { run_calibrate(*args); });
}

BOSFUSE_COMMAND(add_calibrate);

}  // namespace
}  // namespace bosfuse::app
