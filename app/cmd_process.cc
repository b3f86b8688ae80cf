// bosfuse process: a run's frames against its reference frame → BOS probe
// series at the thermocouples (and, unless --probes-only, displacement and
// temperature fields under RUN/fields/), Newton fits and agreement, stored
// in the run (docs/SCHEMA.md, version 2). Progress goes to stderr.

#include <iostream>

#include "app/command.h"
#include "app/run_processing.h"

namespace bosfuse::app {
namespace {

struct ProcessArgs {
  std::string run;
  bool probes_only = false;
  int window_px = 32, step_px = 16, passes = 3, probe_context = 1;
  double max_shift_px = 4;
  std::string geometry;
  std::string mask;
};

void process(const ProcessArgs& args) {
  ProcessOptions options;
  options.probes_only = args.probes_only;
  options.evaluator.set_grid(args.window_px, args.step_px);
  options.evaluator.xcorr.passes = args.passes;
  options.evaluator.xcorr.max_shift_px = args.max_shift_px;
  options.evaluator.xcorr.probe_context_nodes = args.probe_context;
  options.geometry_file = args.geometry;
  options.mask_file = args.mask;
  options.progress = [](const std::string& line) { std::cerr << line << (line.ends_with('\n') ? "" : "\n"); };
  const ProcessReport report = process_run(args.run, options);
  std::cout << report.text;
}

void add_process(CLI::App& root) {
  auto args = std::make_shared<ProcessArgs>();
  CLI::App* cmd = root.add_subcommand(
      "process", "Evaluate a run's frames against its reference: probes, fields, temperatures, fits, agreement");
  cmd->add_option("run", args->run, "Run folder")->required();
  cmd->add_flag("--probes-only", args->probes_only,
                "Evaluate only the windows at the thermocouples' image positions (no field files)");
  cmd->add_option("--window", args->window_px, "Final interrogation window, px")->capture_default_str();
  cmd->add_option("--step", args->step_px, "Grid spacing, px")->capture_default_str();
  cmd->add_option("--passes", args->passes, "Passes (window deformation after the first)")->capture_default_str();
  cmd->add_option("--probe-context", args->probe_context,
                  "Probe mode: grid nodes evaluated around each probe; -1: all the full field depends on (then a "
                  "probe equals the full field there, but is ~40x slower)")
      ->check(CLI::Range(-1, 16))
      ->capture_default_str();
  cmd->add_option("--max-shift", args->max_shift_px, "Largest displacement expected, px")->capture_default_str();
  cmd->add_option("--geometry", args->geometry,
                  "TOML file with [geometry] (and [alignment]); default: the run's config, else built-in defaults");
  cmd->add_option("--mask", args->mask,
                  "Mask image (e.g. the heater's holder): non-zero pixels are not evaluated and the temperature "
                  "field is filled there from its surroundings; a path relative to the run folder or absolute");
  cmd->callback([args] { process(*args); });
}

BOSFUSE_COMMAND(add_process);

}  // namespace
}  // namespace bosfuse::app
