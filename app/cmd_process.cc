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
#include "app/evaluator_arguments.h"
#include "app/progress_display.h"
#include "app/ranks.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "pipeline/process.h"
#include "pipeline/process_frame.h"

namespace bosfuse::app {
namespace {

struct ProcessArgs {
  std::string run;
  bool resume = false;
  EvaluatorArguments evaluator;
  std::optional<std::string> mode, geometry;
  std::optional<int> probe_context, threads, frames_at_once;
};

pipeline::SettingsOverrides overrides(const ProcessArgs& args) {
  pipeline::SettingsOverrides o = settings_overrides(args.evaluator);
  if (args.mode) o.probes_only = *args.mode == "probes";
  o.probe_context_nodes = args.probe_context;
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
  std::cerr << report.text;  // a summary for a person: standard output holds data only
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
  add_evaluator_options(*cmd, args->evaluator, SettingsBase::kStored);
  cmd->add_option("--probe-context", args->probe_context,
                  "Probe mode: grid nodes evaluated around each probe; -1: all the full field depends on (then a "
                  "probe equals the full field there, but is ~40x slower) (default: stored, else 1)")
      ->check(CLI::Range(-1, 16));
  cmd->add_option("--geometry", args->geometry,
                  "TOML file with [geometry] (and [alignment]); default: stored, else the run's experiment file, "
                  "else built-in defaults");
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
