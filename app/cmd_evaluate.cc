// bosfuse evaluate: a reference and a measurement image → a displacement
// field as CSV (x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v) on standard output or in the
// file -o names, optionally a map PNG (--map); the summary goes to standard
// error. With --sequence, a whole folder or glob of frames against one
// reference → one HDF5 file (report/sequence_export.h), with progress on
// standard error and exit status 6 when some frames could not be evaluated.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/command.h"
#include "app/output_stream.h"
#include "app/progress_display.h"
#include "app/ranks.h"
#include "app/run_control.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/preprocess.h"
#include "fusion/scene_match.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/field_csv.h"
#include "pipeline/image_io.h"
#include "pipeline/image_sequence.h"
#include "pipeline/processing_settings.h"
#include "pipeline/sequence_evaluation.h"
#include "report/field_export.h"
#include "report/figures.h"
#include "report/run_input.h"
#include "report/sequence_export.h"

namespace bosfuse::app {
namespace {

using pipeline::read_image;

struct EvaluateArgs {
  std::string reference, measurement, out = "-", map, mask, roi, method = "xcorr", flow = "dis", dis_preset = "medium",
                                      subpixel = "auto", interpolator = "lanczos3", adaptive_refinement = "off",
                                      preprocess = "none";
  std::string sequence_reference, sequence, settings;
  std::vector<std::string> probes;
  int window_px = 16, first_window_px = 0, step_px = 8, passes = 3;
  std::optional<int> threads;
  double max_shift_px = 4, contour_px = 0.1, adaptive_threshold = 4;
  bool arrows = false;
  bool max_shift_given = false;  // --max-shift: an explicit bound, not widened from the scene
};

std::vector<int> parse_ints(const std::string& text, std::size_t count, const std::string& what) {
  std::vector<int> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      values.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw CLI::ValidationError(fmt::format("{} '{}': '{}' is not a whole number", what, text, item));
    }
  }
  if (values.size() != count) throw CLI::ValidationError(fmt::format("{} '{}' needs {} numbers", what, text, count));
  return values;
}

// A point off the image is a typing error, not a probe to flag: say so.
cv::Point2d parse_point(const std::string& text, cv::Size image_size) {
  const auto comma = text.find(',');
  cv::Point2d point;
  try {
    if (comma == std::string::npos) throw std::invalid_argument("no comma");
    point = {std::stod(text.substr(0, comma)), std::stod(text.substr(comma + 1))};
  } catch (const std::exception&) {
    throw CLI::ValidationError("probe '" + text + "' must be x,y in pixels");
  }
  if (!(point.x >= 0 && point.y >= 0 && point.x <= image_size.width - 1 && point.y <= image_size.height - 1)) {
    throw CLI::ValidationError(
        fmt::format("probe '{}' lies outside the {}x{} image", text, image_size.width, image_size.height));
  }
  return point;
}

// The choices only the command line makes (the stored settings have no key for them).
void apply_xcorr_choices(const EvaluateArgs& args, fusion::EvaluatorOptions& options) {
  options.xcorr.first_window_px = args.first_window_px;
  // "auto": the 2-D fit where peaks lock (first pass), 3-point after deformation.
  if (args.subpixel == "gauss3") {
    options.xcorr.subpixel = options.xcorr.refinement_subpixel = fusion::SubpixelEstimator::kGaussian3Point;
  } else if (args.subpixel == "gauss2d") {
    options.xcorr.subpixel = options.xcorr.refinement_subpixel = fusion::SubpixelEstimator::kGaussian2dFit;
  }
  const std::map<std::string, fusion::Interpolator> interpolators{{"cubic", fusion::Interpolator::kCubic},
                                                                  {"lanczos3", fusion::Interpolator::kLanczos3},
                                                                  {"lanczos4", fusion::Interpolator::kLanczos4}};
  options.xcorr.interpolator = interpolators.at(args.interpolator);
  const std::map<std::string, fusion::DisPreset> presets{{"ultrafast", fusion::DisPreset::kUltrafast},
                                                         {"fast", fusion::DisPreset::kFast},
                                                         {"medium", fusion::DisPreset::kMedium}};
  options.flow.dis_preset = presets.at(args.dis_preset);
}

fusion::EvaluatorOptions evaluator_options(const EvaluateArgs& args) {
  fusion::EvaluatorOptions options;
  options.method = args.method == "flow" ? fusion::Method::kOpticalFlow : fusion::Method::kCrossCorrelation;
  cv::Rect roi;
  if (!args.roi.empty()) {
    const auto r = parse_ints(args.roi, 4, "--roi");
    roi = {r[0], r[1], r[2], r[3]};
  }
  options.set_grid(args.window_px, args.step_px, roi);
  options.xcorr.passes = args.passes;
  options.xcorr.max_shift_px = args.max_shift_px;
  options.xcorr.find_search_range = !args.max_shift_given;
  options.xcorr.adaptive_refinement = args.adaptive_refinement == "on";
  options.xcorr.adaptive_threshold = args.adaptive_threshold;
  options.preprocess.method = fusion::parse_preprocessing(args.preprocess).value_or(fusion::Preprocessing::kNone);
  apply_xcorr_choices(args, options);
  const std::map<std::string, fusion::FlowAlgorithm> flows{{"dis", fusion::FlowAlgorithm::kDis},
                                                           {"farneback", fusion::FlowAlgorithm::kFarneback},
                                                           {"tvl1", fusion::FlowAlgorithm::kTvl1}};
  options.flow.algorithm = flows.at(args.flow);
  if (const auto problem = options.Validate(); !problem.empty()) throw CLI::ValidationError(problem);
  return options;
}

void evaluate(const EvaluateArgs& args) {
  const auto options = evaluator_options(args);
  check_output(args.out, "--out");
  if (!args.map.empty()) {
    refuse_standard_output(args.map, "--map", "the image format comes from the file name (.png)");
    if (!args.probes.empty()) throw CLI::ValidationError("--map draws a full field; it cannot be used with --probe");
    check_figure_output(args.map, "--map");
  }
  const cv::Mat reference = read_image(args.reference, "reference");
  const cv::Mat measurement = read_image(args.measurement, "measurement");
  const cv::Mat mask = args.mask.empty() ? cv::Mat() : read_image(args.mask, "mask");
  fusion::EvaluationResult result;
  if (args.probes.empty()) {
    result = fusion::evaluate_displacement(reference, measurement, options, mask);
  } else {
    std::vector<cv::Point2d> points;
    for (const auto& p : args.probes) points.push_back(parse_point(p, reference.size()));
    result = fusion::probe_displacement(reference, measurement, points, options, mask);
  }
  pipeline::log_evaluation(result.summary);
  const auto scene = fusion::match_scene(measurement, reference);
  pipeline::log_warnings(scene.warnings);
  if (!scene.same_scene()) {
    fusion::refuse_vectors(result);  // a pair of two scenes supports no vector
    spdlog::warn("{} against {}: {}; no vector is marked valid", args.measurement, args.reference, scene.Describe());
  }
  OutputStream out(args.out, "--out");
  pipeline::write_csv(result.field, out.stream());
  out.close();
  if (!args.map.empty()) {
    report::MapField map = report::displacement_magnitude_map(result.field, reference.size());
    map.source = args.measurement + " against " + args.reference;
    map.arrows = args.arrows;
    report::write_map_figure(map, args.contour_px, {}, std::nullopt, {900, 650}, report::figure_base(args.map));
  }
  spdlog::info("{}", result.summary.BriefReport());
  spdlog::info("preprocessing: {}", fusion::to_string(options.preprocess.method));
}

// The options the user gave (an option left at its default does not
// override the settings file).
pipeline::SettingsOverrides given_overrides(const EvaluateArgs& args, const CLI::App& cmd) {
  pipeline::SettingsOverrides o;
  auto given = [&](const char* name) { return cmd.count(name) > 0; };
  if (given("--method")) o.method = args.method;
  if (given("--flow")) o.flow_algorithm = args.flow;
  if (given("--window")) o.window_px = args.window_px;
  if (given("--step")) o.step_px = args.step_px;
  if (given("--passes")) o.passes = args.passes;
  if (given("--max-shift")) o.max_shift_px = args.max_shift_px;
  if (given("--adaptive-refinement")) o.adaptive_refinement = args.adaptive_refinement == "on";
  if (given("--adaptive-threshold")) o.adaptive_threshold = args.adaptive_threshold;
  if (given("--preprocess")) o.preprocess = args.preprocess;
  if (given("--roi")) {
    const auto r = parse_ints(args.roi, 4, "--roi");
    o.roi_px = cv::Rect(r[0], r[1], r[2], r[3]);
  }
  if (given("--mask")) o.mask = args.mask;
  return o;
}

// What the file's `settings` attribute holds: the stored settings' keys
// (pipeline/processing_settings.h) for an evaluation without a run.
std::string settings_json(const pipeline::ProcessingSettings& settings, const EvaluateArgs& args) {
  auto j = pipeline::to_json(settings);
  j.erase("mode");
  j.erase("probe_context_nodes");
  j.erase("geometry");
  j["first_window_px"] = settings.evaluator.xcorr.first_window_px;
  j["subpixel"] = args.subpixel;
  j["interpolator"] = args.interpolator;
  j["dis_preset"] = args.dis_preset;
  j["source"] = settings.source;
  return j.dump();
}

// What the other ranks of an MPI job are sent: the frames as rank 0 listed
// them, and the settings it resolved, which each rank resolves again from
// the same command line and must find the same.
pipeline::Bytes sequence_plan(const std::vector<std::string>& frames, const std::string& settings) {
  return nlohmann::json::to_cbor(nlohmann::json{{"frames", frames}, {"settings", settings}});
}

pipeline::FrameWork sequence_frame_work(const EvaluateArgs& args, const pipeline::ProcessingSettings& settings,
                                        const pipeline::Bytes& plan) {
  const auto j = nlohmann::json::from_cbor(plan);
  if (j.at("settings").get<std::string>() != settings_json(settings, args)) {
    throw std::runtime_error("the settings resolved here differ from rank 0's: is " +
                             (args.settings.empty() ? std::string("the mask") : args.settings) +
                             " the same file on every node?");
  }
  auto evaluator =
      std::make_shared<pipeline::SequenceEvaluator>(args.sequence_reference, settings.evaluator, settings.mask);
  auto frames = std::make_shared<std::vector<std::string>>(j.at("frames").get<std::vector<std::string>>());
  return [evaluator, frames](std::size_t i) { return pipeline::result_bytes(evaluator->evaluate(frames->at(i))); };
}

// Rank 0's side, or the whole job in one process: every frame evaluated,
// here or by the distributor's ranks, and written in order.
void write_sequence(const EvaluateArgs& args, const pipeline::ProcessingSettings& settings,
                    pipeline::FrameDistributor* distributor) {
  // The reference, the mask and the settings are checked before anything is written.
  pipeline::SequenceEvaluator evaluator(args.sequence_reference, settings.evaluator, settings.mask);
  const auto sequence = pipeline::list_image_sequence(args.sequence, {args.sequence_reference, settings.mask});
  for (const auto& file : sequence.left_out) spdlog::info("{}: the reference or the mask, not a frame", file);
  report::SequenceFieldWriter writer(
      args.out, {args.sequence_reference, settings_json(settings, args), sequence.frames, evaluator.grid()});

  const std::atomic<bool>& stop = stop_requested_by_signal();
  ProgressDisplay display;
  std::size_t failed = 0;
  auto take = [&](std::size_t i, const pipeline::SequenceFrameResult& result) {
    if (!result.ok()) {
      ++failed;
      const std::string line = fmt::format("frame {}: {}", result.name, result.status);
      // Under --quiet the display is silent, but a failed frame is a warning all the same.
      if (spdlog::should_log(spdlog::level::info)) {
        display.note("warning: " + line);
      } else {
        spdlog::warn("{}", line);
      }
    } else {
      spdlog::debug("{}: {}", result.name, result.summary.BriefReport());
    }
    writer.write(i, result);
    display.step(i + 1, sequence.frames.size(), result.name);
  };
  const std::size_t count = sequence.frames.size();
  std::size_t taken = 0;
  if (distributor) {
    taken = distributor->run(
        sequence_plan(sequence.frames, settings_json(settings, args)), count,
        [&](std::size_t i) { return pipeline::result_bytes(evaluator.evaluate(sequence.frames[i])); },
        [&](std::size_t i, const pipeline::Bytes& bytes) { take(i, pipeline::result_from_bytes(bytes)); }, &stop);
  } else {
    for (; taken < count && !stop; ++taken) take(taken, evaluator.evaluate(sequence.frames[taken]));
  }
  if (taken < count) throw CommandFailure(kExitStopped, "stopped on request; nothing was written to " + args.out);
  display.finish();
  if (distributor) spdlog::info("{}", distributor->brief_report());
  const auto written = writer.commit();
  spdlog::info("wrote {} and {}: {} of {} frames evaluated, on a {}x{} grid", written.hdf5_path.string(),
               written.xdmf_path.string(), written.frames_ok, written.frames, evaluator.grid().cols,
               evaluator.grid().rows);
  if (failed > 0) {
    throw CommandFailure(
        kExitSomeFramesFailed,
        fmt::format("{} of {} frames could not be evaluated (named above; their status is in {}:/status)", failed,
                    sequence.frames.size(), args.out));
  }
}

void evaluate_sequence(const EvaluateArgs& args, const CLI::App& cmd) {
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
  pipeline::ProcessingSettings settings = pipeline::resolve_runless_settings(args.settings, given_overrides(args, cmd));
  if (settings.probes_only) {
    throw std::runtime_error(args.settings +
                             ": mode = \"probes\" needs a run's thermocouples; a sequence is evaluated in full fields");
  }
  apply_xcorr_choices(args, settings.evaluator);
  if (const auto problem = settings.evaluator.Validate(); !problem.empty()) throw CLI::ValidationError(problem);
  spdlog::info("settings: {} ({})", pipeline::describe(settings), settings.source);

  run_on_ranks(
      args.threads, [&](pipeline::FrameDistributor* distributor) { write_sequence(args, settings, distributor); },
      [&](const pipeline::Bytes& plan) { return sequence_frame_work(args, settings, plan); });
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
  cmd->add_option("--window", args->window_px, "Final interrogation window, px (8..128)")->capture_default_str();
  cmd->add_option("--first-window", args->first_window_px, "First-pass window, px (halved each pass down to --window)");
  cmd->add_option("--step", args->step_px, "Grid spacing, px")->capture_default_str();
  cmd->add_option("--passes", args->passes, "Passes at most (window deformation after the first)")
      ->capture_default_str();
  cmd->add_option("--max-shift", args->max_shift_px,
                  "Largest displacement expected, px: an explicit search bound. Unset, the search starts at 4 px and "
                  "a sample of the scene widens it (with a larger first window) when its peaks lie on the bound")
      ->capture_default_str();
  cmd->add_option("--method", args->method, "xcorr or flow")
      ->check(CLI::IsMember({"xcorr", "flow"}))
      ->capture_default_str();
  cmd->add_option("--flow", args->flow, "Optical flow algorithm: dis, farneback, tvl1")
      ->check(CLI::IsMember({"dis", "farneback", "tvl1"}))
      ->capture_default_str();
  cmd->add_option("--dis-preset", args->dis_preset,
                  "DIS preset: medium (variational refinement, ~230 bytes a pixel in all), fast, or ultrafast (~60)")
      ->check(CLI::IsMember({"ultrafast", "fast", "medium"}))
      ->capture_default_str();
  cmd->add_option("--subpixel", args->subpixel,
                  "Peak estimator: auto (2-D Gaussian fit, then 3-point after deformation), gauss2d or gauss3")
      ->check(CLI::IsMember({"auto", "gauss2d", "gauss3"}))
      ->capture_default_str();
  cmd->add_option("--interpolator", args->interpolator, "Deformation interpolator: lanczos3, lanczos4 or cubic")
      ->check(CLI::IsMember({"lanczos3", "lanczos4", "cubic"}))
      ->capture_default_str();
  cmd->add_option("--adaptive-refinement", args->adaptive_refinement,
                  "on: refinement passes only where the first pass found a displacement above the noise floor")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  cmd->add_option("--adaptive-threshold", args->adaptive_threshold,
                  "Adaptive refinement: refine where the shift or its gradient exceeds this many times the first "
                  "pass's noise floor")
      ->capture_default_str();
  cmd->add_option("--preprocess", args->preprocess,
                  "Filter both images first: none, normalize (local contrast), highpass (background subtraction) or "
                  "minmax (local min-max); docs/CONFIG.md says when each helps")
      ->check(CLI::Validator(
          [](std::string& name) {
            return fusion::parse_preprocessing(name) ? std::string()
                                                     : "must be one of " + fusion::preprocessing_names();
          },
          "NAME"))
      ->capture_default_str();
  cmd->add_option("--mask", args->mask, "Mask image: non-zero pixels are not evaluated");
  cmd->add_option("--roi", args->roi, "Region of interest x,y,w,h in pixels");
  cmd->add_option("--probe", args->probes, "Evaluate only the window centred at x,y (repeatable)");
  auto* map_option = cmd->add_option("--map", args->map, "Also draw the displacement magnitude map to this PNG");
  cmd->add_flag("--arrows", args->arrows, "With --map: draw the displacement vectors as arrows over the colours")
      ->needs(map_option);
  cmd->add_option("--contour", args->contour_px, "Contour spacing of the map, px (0: none)")->capture_default_str();
  cmd->callback([args, cmd] {
    args->max_shift_given = cmd->count("--max-shift") > 0;
    evaluate_command(*args, *cmd);
  });
}

BOSFUSE_COMMAND(add_evaluate);

}  // namespace
}  // namespace bosfuse::app
