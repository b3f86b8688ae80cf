// bosfuse calibrate: fits each thermocouple's rise above its reading at the
// reference frame against the BOS shift at its image position (°C per px of
// shift, through the origin, with standard uncertainty) and stores it in the
// run; a later `bosfuse process` converts probe shifts with it.

#include <iostream>

#include "app/command.h"
#include "pipeline/calibrate.h"

namespace bosfuse::app {
namespace {

struct CalibrateArgs {
  std::string run;
  std::string geometry;
  std::optional<double> camera_offset_s;
  double estimate_offset_s = 0;
};

void add_calibrate(CLI::App& root) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = root.add_subcommand(
      "calibrate", "Fit °C per px of shift at each thermocouple from a processed run and store it in the run");
  cmd->add_option("run", args->run, "Run folder (processed: `bosfuse process RUN --mode probes` is enough)")
      ->required();
  cmd->add_option("--geometry", args->geometry, "TOML file whose [alignment] camera_offset_s is used");
  cmd->add_option("--camera-offset", args->camera_offset_s,
                  "Camera clock offset, experiment s: a frame stamped t happened at t + offset");
  cmd->add_option("--estimate-offset", args->estimate_offset_s,
                  "Estimate the camera clock offset within +-this many seconds (needs a feature in the record)");
  cmd->callback([args] {
    pipeline::CalibrateOptions options;
    options.geometry_file = args->geometry;
    options.camera_offset_s = args->camera_offset_s;
    options.estimate_offset_max_s = args->estimate_offset_s;
    std::cout << pipeline::calibrate_run(args->run, options);
  });
}

BOSFUSE_COMMAND(add_calibrate);

}  // namespace
}  // namespace bosfuse::app
