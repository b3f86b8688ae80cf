// bosfuse process: a run's frames against its reference frame → BOS probe
// series at the thermocouples (and, unless in probe mode, displacement and
// temperature fields), Newton fits and agreement, stored in the run with
// the settings used (pipeline/process.h). With no options the run's stored
// settings are used again; options override them and are stored in turn.
// Progress goes to stderr, the summary to stdout. Started by mpirun or srun,
// the frames are spread over the job's ranks and rank 0 alone writes the
// run (app/ranks.h).

#include <iostream>

#include "app/command.h"
#include "app/progress_display.h"
#include "app/ranks.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "fusion/preprocess.h"
#include "pipeline/process.h"
#include "pipeline/process_frame.h"

namespace bosfuse::app {
namespace {

struct ProcessArgs {
  std::string run;
  bool resume = false;
  std::optional<std::string> mode, method, mask, geometry, roi;
  std::optional<int> window_px, step_px, passes, probe_context, threads, frames_at_once;
  std::optional<double> max_shift_px, adaptive_threshold;
  std::optional<std::string> adaptive_refinement, preprocess;
};

cv::Rect parse_roi(const std::string& text) {
  int x = 0, y = 0, w = 0, h = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &x, &y, &w, &h, &tail) != 4 || w <= 0 || h <= 0 || x < 0 || y < 0) {
    throw std::runtime_error("--roi '" + text + "': expected x,y,width,height in pixels");
  }
  return {x, y, w, h};
}

pipeline::SettingsOverrides overrides(const ProcessArgs& args) {
  pipeline::SettingsOverrides o;
  if (args.mode) o.probes_only = *args.mode == "probes";
  o.method = args.method;
  o.window_px = args.window_px;
  o.step_px = args.step_px;
  o.passes = args.passes;
  o.probe_context_nodes = args.probe_context;
  o.max_shift_px = args.max_shift_px;
  if (args.adaptive_refinement) o.adaptive_refinement = *args.adaptive_refinement == "on";
  o.adaptive_threshold = args.adaptive_threshold;
  o.preprocess = args.preprocess;
  if (args.roi) o.roi_px = parse_roi(*args.roi);
  o.mask = args.mask;
  o.geometry_file = args.geometry;
  return o;
}

void process(const ProcessArgs& args, pipeline::FrameDistributor* distributor) {
  pipeline::ProcessOptions options;
  options.distributor = distributor;
  if (args.frames_at_once) options.frames_at_once = *args.frames_at_once;
  options.overrides = overrides(args);
  options.resume = args.resume;
  options.stop = &stop_requested_by_signal();
  ProgressDisplay display;
  options.progress = [&](const pipeline::ProcessProgress& p) {
    p.frame ? display.step(p.done, p.total, p.line) : display.note(p.line);
  };
  const auto report = pipeline::process_run(args.run, options);
  display.finish();
  std::cout << report.text;
  if (!report.complete) throw CommandFailure(kExitStopped, "processing stopped on request");
}

void add_process(CLI::App& root) {
  auto args = std::make_shared<ProcessArgs>();
  CLI::App* cmd = root.add_subcommand(
      "process",
      "Evaluate a run's frames against its reference: probes, fields, temperatures, fits, agreement. Without "
      "options the run's stored settings are used again; options change them and are stored with the results");
  cmd->add_option("run", args->run, "Run folder")->required()->transform(run_folder_argument());
  cmd->add_flag("--resume", args->resume,
                "Continue the run's interrupted processing with its own settings from the first frame it had not "
                "finished");
  cmd->add_option("--mode", args->mode,
                  "full: displacement and temperature fields of every frame; probes: only the windows at the "
                  "thermocouples' image positions (default: stored, else full)")
      ->check(CLI::IsMember({"full", "probes"}));
  cmd->add_option("--method", args->method, "xcorr or flow (default: stored, else xcorr)")
      ->check(CLI::IsMember({"xcorr", "flow"}));
  cmd->add_option("--window", args->window_px, "Final interrogation window, px (default: stored, else 16)");
  cmd->add_option("--step", args->step_px, "Grid spacing, px (default: stored, else 8)");
  cmd->add_option("--passes", args->passes, "Passes, window deformation after the first (default: stored, else 3)");
  cmd->add_option("--probe-context", args->probe_context,
                  "Probe mode: grid nodes evaluated around each probe; -1: all the full field depends on (then a "
                  "probe equals the full field there, but is ~40x slower) (default: stored, else 1)")
      ->check(CLI::Range(-1, 16));
  cmd->add_option("--max-shift", args->max_shift_px, "Largest displacement expected, px (default: stored, else 4)");
  cmd->add_option("--adaptive-refinement", args->adaptive_refinement,
                  "on: refinement passes only where the first pass found a displacement above the noise floor "
                  "(docs/CONFIG.md) (default: stored, else off)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--adaptive-threshold", args->adaptive_threshold,
                  "Adaptive refinement: refine where the shift or its gradient exceeds this many times the first "
                  "pass's noise floor (default: stored, else 4)");
  cmd->add_option("--preprocess", args->preprocess,
                  "Filter reference and frames first: none, normalize, highpass or minmax (docs/CONFIG.md) "
                  "(default: stored, else none)")
      ->check(CLI::Validator(
          [](std::string& name) {
            return fusion::parse_preprocessing(name) ? std::string()
                                                     : "must be one of " + fusion::preprocessing_names();
          },
          "NAME"));
  cmd->add_option("--roi", args->roi, "Region of interest x,y,width,height in pixels (default: stored, else all)");
  cmd->add_option("--geometry", args->geometry,
                  "TOML file with [geometry] (and [alignment]); default: stored, else the run's experiment file, "
                  "else built-in defaults");
  cmd->add_option("--mask", args->mask,
                  "Mask image (e.g. the heater's holder): non-zero pixels are not evaluated; a path relative to the "
                  "run folder, or absolute (then copied into the run); '' for none (default: stored, else none)");
  cmd->add_option("--frames-at-once", args->frames_at_once,
                  "Frames evaluated side by side, each with its own evaluator (~600 MB at 16 MP); 1: one at a time "
                  "(default: one per core, at most 4; under mpirun each rank takes one at a time)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--threads", args->threads,
                  "Evaluation threads (per MPI rank under mpirun/srun); default: every core, or in an MPI job the "
                  "rank's share of its node");
  cmd->callback([args] {
    run_on_ranks(
        args->threads, [&](pipeline::FrameDistributor* distributor) { process(*args, distributor); },
        pipeline::planned_frame_work);
  });
}

BOSFUSE_COMMAND(add_process);

}  // namespace
}  // namespace bosfuse::app
