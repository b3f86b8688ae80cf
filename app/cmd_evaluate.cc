// bosfuse evaluate: a reference and a measurement image → a displacement
// field as CSV (x,y,u,v,valid,peak_ratio) on standard output or in the
// file -o names, optionally a map PNG (--map); the summary goes to standard
// error.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <map>
#include <sstream>

#include "app/command.h"
#include "app/output_stream.h"
#include "fusion/displacement_evaluator.h"
#include "pipeline/image_io.h"
#include "report/figures.h"
#include "report/run_input.h"

namespace bosfuse::app {
namespace {

using pipeline::read_image;

struct EvaluateArgs {
  std::string reference, measurement, out = "-", map, mask, roi, method = "xcorr", flow = "dis", subpixel = "auto",
                                      interpolator = "lanczos3", adaptive_refinement = "off";
  std::vector<std::string> probes;
  int window_px = 16, first_window_px = 0, step_px = 8, passes = 3;
  double max_shift_px = 4, contour_px = 0.1, adaptive_threshold = 4;
};

std::vector<int> parse_ints(const std::string& text, std::size_t count, const std::string& what) {
  std::vector<int> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      values.push_back(std::stoi(item));
    } catch (const std::exception&) {
      throw std::runtime_error(fmt::format("{} '{}': '{}' is not a whole number", what, text, item));
    }
  }
  if (values.size() != count) throw std::runtime_error(fmt::format("{} '{}' needs {} numbers", what, text, count));
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
    throw std::runtime_error("probe '" + text + "' must be x,y in pixels");
  }
  if (!(point.x >= 0 && point.y >= 0 && point.x <= image_size.width - 1 && point.y <= image_size.height - 1)) {
    throw std::runtime_error(
        fmt::format("probe '{}' lies outside the {}x{} image", text, image_size.width, image_size.height));
  }
  return point;
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
  options.xcorr.first_window_px = args.first_window_px;
  options.xcorr.passes = args.passes;
  options.xcorr.max_shift_px = args.max_shift_px;
  options.xcorr.adaptive_refinement = args.adaptive_refinement == "on";
  options.xcorr.adaptive_threshold = args.adaptive_threshold;
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
  const std::map<std::string, fusion::FlowAlgorithm> flows{{"dis", fusion::FlowAlgorithm::kDis},
                                                           {"farneback", fusion::FlowAlgorithm::kFarneback},
                                                           {"tvl1", fusion::FlowAlgorithm::kTvl1}};
  options.flow.algorithm = flows.at(args.flow);
  if (const auto problem = options.Validate(); !problem.empty()) throw std::runtime_error(problem);
  return options;
}

void evaluate(const EvaluateArgs& args) {
  const auto options = evaluator_options(args);
  if (!args.map.empty()) {
    refuse_standard_output(args.map, "--map", "the image format comes from the file name (.png)");
    if (!args.probes.empty()) throw std::runtime_error("--map draws a full field; it cannot be used with --probe");
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
  OutputStream out(args.out);
  fusion::write_csv(result.field, out.stream());
  out.close();
  if (!args.map.empty()) {
    report::MapField map = report::displacement_magnitude_map(result.field, reference.size());
    map.source = args.measurement + " against " + args.reference;
    report::write_map_figure(map, args.contour_px, {}, std::nullopt, {900, 650}, report::figure_base(args.map));
  }
  spdlog::info("{}", result.summary.BriefReport());
}

void add_evaluate(CLI::App& root) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* cmd =
      root.add_subcommand("evaluate", "Displacement field of an image pair (CSV: x,y,u,v,valid,peak_ratio)");
  cmd->add_option("reference", args->reference, "Reference image (no flow)")->required();
  cmd->add_option("measurement", args->measurement, "Measurement image (through the flow)")->required();
  cmd->add_option("--out,-o", args->out, "CSV file to write; '-' (the default): standard output");
  cmd->add_option("--window", args->window_px, "Final interrogation window, px (8..128)")->capture_default_str();
  cmd->add_option("--first-window", args->first_window_px, "First-pass window, px (halved each pass down to --window)");
  cmd->add_option("--step", args->step_px, "Grid spacing, px")->capture_default_str();
  cmd->add_option("--passes", args->passes, "Passes at most (window deformation after the first)")
      ->capture_default_str();
  cmd->add_option("--max-shift", args->max_shift_px, "Largest displacement expected, px (bounds the search)")
      ->capture_default_str();
  cmd->add_option("--method", args->method, "xcorr or flow")
      ->check(CLI::IsMember({"xcorr", "flow"}))
      ->capture_default_str();
  cmd->add_option("--flow", args->flow, "Optical flow algorithm: dis, farneback, tvl1")
      ->check(CLI::IsMember({"dis", "farneback", "tvl1"}))
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
  cmd->add_option("--mask", args->mask, "Mask image: non-zero pixels are not evaluated");
  cmd->add_option("--roi", args->roi, "Region of interest x,y,w,h in pixels");
  cmd->add_option("--probe", args->probes, "Evaluate only the window centred at x,y (repeatable)");
  cmd->add_option("--map", args->map, "Also draw the displacement magnitude map to this PNG");
  cmd->add_option("--contour", args->contour_px, "Contour spacing of the map, px (0: none)")->capture_default_str();
  cmd->callback([args] { evaluate(*args); });
}

BOSFUSE_COMMAND(add_evaluate);

}  // namespace
}  // namespace bosfuse::app
