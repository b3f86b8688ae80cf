#include "app/evaluator_arguments.h"

#include <fmt/format.h>

#include <sstream>
#include <vector>

#include "fusion/optical_flow.h"
#include "fusion/preprocess.h"
#include "pipeline/evaluation_choices.h"

namespace bosfuse::app {
namespace {

// An option's help over the defaults (with the default shown) and over a
// run's stored settings.
struct OptionHelp {
  const char* over_defaults;
  const char* over_stored;
  const char* default_value = nullptr;  // shown over the defaults
};

template <typename T>
CLI::Option* add(CLI::App& cmd, const std::string& name, T& value, const OptionHelp& help, SettingsBase base) {
  CLI::Option* option =
      cmd.add_option(name, value, base == SettingsBase::kDefaults ? help.over_defaults : help.over_stored);
  if (base == SettingsBase::kDefaults && help.default_value) option->default_str(help.default_value);
  return option;
}

CLI::Validator preprocessing_name() {
  return CLI::Validator(
      [](std::string& name) {
        return fusion::parse_preprocessing(name) ? std::string() : "must be one of " + fusion::preprocessing_names();
      },
      "NAME");
}

void add_grid_options(CLI::App& cmd, EvaluatorArguments& args, SettingsBase base) {
  add(cmd, "--method", args.method, {"xcorr or flow", "xcorr or flow (default: stored, else xcorr)", "xcorr"}, base)
      ->check(CLI::IsMember({"xcorr", "flow"}));
  add(cmd, "--window", args.window_px,
      {"Final interrogation window, px (8..128)", "Final interrogation window, px (default: stored, else 16)", "16"},
      base);
  add(cmd, "--step", args.step_px, {"Grid spacing, px", "Grid spacing, px (default: stored, else 8)", "8"}, base);
  add(cmd, "--passes", args.passes,
      {"Passes at most (window deformation after the first)",
       "Passes, window deformation after the first (default: stored, else 3)", "3"},
      base);
  add(cmd, "--max-shift", args.max_shift_px,
      {"Largest displacement expected, px: an explicit search bound. Unset, the search starts at 4 px and a sample "
       "of the scene widens it (with a larger first window) when its peaks lie on the bound",
       "Largest displacement expected, px (default: stored, else 4)", "4"},
      base);
}

void add_refinement_options(CLI::App& cmd, EvaluatorArguments& args, SettingsBase base) {
  add(cmd, "--adaptive-refinement", args.adaptive_refinement,
      {"on: refinement passes only where the first pass found a displacement above the noise floor",
       "on: refinement passes only where the first pass found a displacement above the noise floor "
       "(docs/CONFIG.md) (default: stored, else off)",
       "off"},
      base)
      ->check(CLI::IsMember({"on", "off"}));
  add(cmd, "--adaptive-threshold", args.adaptive_threshold,
      {"Adaptive refinement: refine where the shift or its gradient exceeds this many times the first pass's "
       "noise floor",
       "Adaptive refinement: refine where the shift or its gradient exceeds this many times the first pass's "
       "noise floor (default: stored, else 4)",
       "4"},
      base);
  add(cmd, "--preprocess", args.preprocess,
      {"Filter both images first: none, normalize (local contrast), highpass (background subtraction), minmax "
       "(local min-max) or denoise (adaptive Wiener); docs/CONFIG.md says when each helps",
       "Filter reference and frames first: none, normalize, highpass, minmax or denoise (docs/CONFIG.md) (default: "
       "stored, else none)",
       "none"},
      base)
      ->check(preprocessing_name());
}

void add_region_options(CLI::App& cmd, EvaluatorArguments& args, SettingsBase base) {
  add(cmd, "--mask", args.mask,
      {"Mask image: non-zero pixels are not evaluated",
       "Mask image (e.g. the heater's holder): non-zero pixels are not evaluated; a path relative to the run "
       "folder, or absolute (then copied into the run); '' for none (default: stored, else none)"},
      base);
  add(cmd, "--roi", args.roi,
      {"Region of interest x,y,w,h in pixels",
       "Region of interest x,y,width,height in pixels (default: stored, else all)"},
      base);
}

int whole_number(const std::string& item, const std::string& text, const std::string& option) {
  try {
    std::size_t used = 0;
    const int value = std::stoi(item, &used);
    if (used == item.size()) return value;
  } catch (const std::exception&) {
    // the message below
  }
  throw CLI::ValidationError(fmt::format("{} '{}': '{}' is not a whole number", option, text, item));
}

}  // namespace

void add_evaluator_options(CLI::App& cmd, EvaluatorArguments& args, SettingsBase base) {
  add_grid_options(cmd, args, base);
  add_refinement_options(cmd, args, base);
  add_region_options(cmd, args, base);
}

void add_evaluation_choices(CLI::App& cmd, EvaluatorArguments& args) {
  cmd.add_option("--first-window", args.first_window_px, "First-pass window, px (halved each pass down to --window)");
  cmd.add_option("--flow", args.flow, "Optical flow algorithm: dis, farneback, tvl1")
      ->check(CLI::IsMember(fusion::flow_algorithm_names()))
      ->default_str("dis");
  cmd.add_option("--dis-preset", args.dis_preset,
                 "DIS preset: medium (variational refinement, ~230 bytes a pixel in all), fast, or ultrafast (~60)")
      ->check(CLI::IsMember(fusion::dis_preset_names()))
      ->capture_default_str();
  cmd.add_option("--subpixel", args.subpixel,
                 "Peak estimator: auto (2-D Gaussian fit, then 3-point after deformation), gauss2d or gauss3")
      ->check(CLI::IsMember({"auto", "gauss2d", "gauss3"}))
      ->capture_default_str();
  cmd.add_option("--interpolator", args.interpolator, "Deformation interpolator: bspline5 (prefiltered quintic B-spline), bspline3, lanczos3, lanczos4 or cubic")
      ->check(CLI::IsMember({"bspline5", "bspline3", "lanczos3", "lanczos4", "cubic"}))
      ->capture_default_str();
}

pipeline::SettingsOverrides settings_overrides(const EvaluatorArguments& args) {
  pipeline::SettingsOverrides o;
  o.method = args.method;
  o.flow_algorithm = args.flow;
  o.window_px = args.window_px;
  o.step_px = args.step_px;
  o.passes = args.passes;
  o.max_shift_px = args.max_shift_px;
  if (args.adaptive_refinement) o.adaptive_refinement = *args.adaptive_refinement == "on";
  o.adaptive_threshold = args.adaptive_threshold;
  o.preprocess = args.preprocess;
  if (args.roi) o.roi_px = parse_roi(*args.roi);
  o.mask = args.mask;
  return o;
}

void apply_evaluation_choices(const EvaluatorArguments& args, fusion::EvaluatorOptions& options) {
  pipeline::apply_evaluation_choices({args.first_window_px, args.dis_preset, args.subpixel, args.interpolator}, options);
}

cv::Point2d parse_probe(const std::string& text, cv::Size image_size) {
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

cv::Rect parse_roi(const std::string& text, const std::string& option) {
  std::vector<int> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) values.push_back(whole_number(item, text, option));
  if (values.size() != 4) throw CLI::ValidationError(fmt::format("{} '{}' needs 4 numbers", option, text));
  const cv::Rect roi(values[0], values[1], values[2], values[3]);
  if (roi.x < 0 || roi.y < 0 || roi.width <= 0 || roi.height <= 0) {
    throw CLI::ValidationError(fmt::format(
        "{} '{}': expected x,y,width,height in pixels, x and y at least 0, width and height at least 1", option, text));
  }
  return roi;
}

}  // namespace bosfuse::app
