// bosfuse evaluate: a reference and a measurement image → a displacement
// field as CSV (x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v) on standard output or in the
// file -o names, optionally a map PNG (--map); the summary goes to standard
// error. With --sequence, a whole folder or glob of frames against one
// reference → one HDF5 file (report/sequence_export.h), with progress on
// standard error and exit status 6 when some frames could not be evaluated.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "app/command.h"
#include "app/evaluator_arguments.h"
#include "app/output_stream.h"
#include "app/run_control.h"
#include "app/sequence_file.h"
#include "pipeline/field_csv.h"
#include "pipeline/pair_evaluation.h"
#include "pipeline/sequence_run.h"
#include "report/field_export.h"
#include "report/figures.h"
#include "report/run_input.h"

namespace bosfuse::app {
namespace {

struct EvaluateArgs {
  std::string reference, measurement, out = "-", map;
  std::string sequence_reference, sequence, settings;
  std::vector<std::string> probes;
  EvaluatorArguments evaluator;
  std::optional<int> threads;
  double contour_px = 0.1;
  bool arrows = false;
};

void evaluate(const EvaluateArgs& args) {
  auto options = pipeline::default_evaluator_with(settings_overrides(args.evaluator));
  apply_evaluation_choices(args.evaluator, options);
  if (const auto problem = options.Validate(); !problem.empty()) throw CLI::ValidationError(problem);
  check_output(args.out, "--out");
  if (!args.map.empty()) {
    refuse_standard_output(args.map, "--map", "the image format comes from the file name (.png)");
    if (!args.probes.empty()) throw CLI::ValidationError("--map draws a full field; it cannot be used with --probe");
    check_figure_output(args.map, "--map");
  }
  const auto pair = pipeline::read_image_pair(args.reference, args.measurement, args.evaluator.mask.value_or(""));
  std::vector<cv::Point2d> points;
  for (const auto& p : args.probes) points.push_back(parse_probe(p, pair.reference.size()));
  const auto result = pipeline::evaluate_image_pair(pair, options, points);
  OutputStream out(args.out, "--out");
  pipeline::write_csv(result.field, out.stream());
  out.close();
  if (!args.map.empty()) {
    report::MapField map = report::displacement_magnitude_map(result.field, pair.reference.size());
    map.source = args.measurement + " against " + args.reference;
    map.arrows = args.arrows;
    report::write_map_figure(map, args.contour_px, {}, std::nullopt, {900, 650}, report::figure_base(args.map));
  }
  spdlog::info("{}", result.summary.BriefReport());
  spdlog::info("preprocessing: {}", fusion::to_string(options.preprocess.method));
}

void check_sequence_arguments(const EvaluateArgs& args, const CLI::App& cmd) {
  if (!args.reference.empty() || !args.measurement.empty()) {
    throw CLI::ValidationError("--sequence takes the reference as --reference REF, not as a positional image");
  }
  if (args.sequence_reference.empty()) throw CLI::ValidationError("--sequence needs --reference REF");
  if (args.out == "-") {
    throw CLI::ValidationError("--sequence needs --out FILE.h5: the fields go to an HDF5 file, not standard output");
  }
  check_output(args.out, "--out");
  check_output(report::xdmf_path_for(args.out).string(), "--out (its .xmf sidecar)");
  for (const char* pair_only : {"--probe", "--map", "--contour", "--arrows"}) {
    if (cmd.count(pair_only) > 0) {
      throw CLI::ValidationError(std::string(pair_only) + " is for an image pair, not --sequence");
    }
  }
}

void evaluate_sequence(const EvaluateArgs& args, const CLI::App& cmd) {
  check_sequence_arguments(args, cmd);
  pipeline::SequenceRunOptions options = sequence_run_options(args.settings, args.evaluator);
  options.reference = args.sequence_reference;
  options.sequence = args.sequence;
  spdlog::info("settings: {} ({})", pipeline::describe(options.settings), options.settings.source);
  write_sequence_file(std::move(options), args.out, args.threads);
}

void evaluate_command(const EvaluateArgs& args, const CLI::App& cmd) {
  if (!args.sequence.empty()) return evaluate_sequence(args, cmd);
  if (!args.sequence_reference.empty() || !args.settings.empty()) {
    throw CLI::ValidationError("--reference and --settings go with --sequence; an image pair is REF MEAS");
  }
  if (args.reference.empty() || args.measurement.empty()) {
    throw CLI::ValidationError(
        "evaluate needs REF MEAS (an image pair), or --reference REF --sequence GLOB --out FILE.h5");
  }
  evaluate(args);
}

void add_evaluate(CLI::App& root) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* cmd = root.add_subcommand(
      "evaluate",
      "Displacement field of an image pair (CSV: x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v), or of every frame of a "
      "sequence "
      "against one reference (--sequence: HDF5)");
  cmd->add_option("reference", args->reference, "Reference image (no flow)");
  cmd->add_option("measurement", args->measurement, "Measurement image (through the flow)");
  cmd->add_option("--out,-o", args->out,
                  "CSV file to write; '-' (the default): standard output. With --sequence: the HDF5 file (required), "
                  "its .xmf sidecar beside it");
  cmd->add_option("--reference", args->sequence_reference, "With --sequence: the reference image");
  cmd->add_option("--sequence", args->sequence,
                  "Evaluate every frame a glob pattern (quoted: 'frames/*.tif') or a folder names, in natural order "
                  "(frame_2 before frame_10), against --reference; exit status 6 when some frames failed");
  cmd->add_option("--settings", args->settings,
                  "With --sequence: a TOML file whose [processing] table sets the evaluation (the keys a run stores: "
                  "method, window_px, step_px, passes, max_shift_px, roi_px, mask ...); options given override it");
  cmd->add_option("--threads", args->threads,
                  "With --sequence: evaluation threads (per MPI rank under mpirun/srun); default: every core, or in "
                  "an MPI job the rank's share of its node");
  add_evaluator_options(*cmd, args->evaluator, SettingsBase::kDefaults);
  add_evaluation_choices(*cmd, args->evaluator);
  cmd->add_option("--probe", args->probes, "Evaluate only the window centred at x,y (repeatable)");
  auto* map_option = cmd->add_option("--map", args->map, "Also draw the displacement magnitude map to this PNG");
  cmd->add_flag("--arrows", args->arrows, "With --map: draw the displacement vectors as arrows over the colours")
      ->needs(map_option);
  cmd->add_option("--contour", args->contour_px, "Contour spacing of the map, px (0: none)")->capture_default_str();
  cmd->callback([args, cmd] { evaluate_command(*args, *cmd); });
}

BOSFUSE_COMMAND(add_evaluate);

}  // namespace
}  // namespace bosfuse::app
