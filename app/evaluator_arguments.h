#pragma once
// The evaluator's options on the command line, one definition for every
// command that evaluates images (`evaluate`, `process`): their names,
// checks and help, and the one mapping from what was given to
// pipeline::SettingsOverrides. An option left out stays unset, so it does
// not override the settings it is laid over (a run's stored ones, a
// settings file's, or the defaults). The help says what that base is:
// `evaluate` shows the defaults, `process` says "default: stored, else ...".
// The ROI and probe parsers here are the only ones; a ROI is
// x,y,width,height in whole pixels, x and y at least 0, width and height at
// least 1.
//
// `evaluate` also has the choices the stored settings have no key for
// (first window, subpixel estimator, interpolator, flow algorithm, DIS
// preset): add_evaluation_choices() and apply_evaluation_choices().

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "fusion/displacement_evaluator.h"
#include "pipeline/processing_settings.h"

namespace bosfuse::app {

struct EvaluatorArguments {
  std::optional<std::string> method, adaptive_refinement, preprocess, roi, mask;
  std::optional<int> window_px, step_px, passes;
  std::optional<double> max_shift_px, adaptive_threshold;
  // evaluate's own choices (add_evaluation_choices)
  std::optional<std::string> flow;
  int first_window_px = 0;
  std::string dis_preset = "medium", subpixel = "auto", interpolator = "bspline5";
};

// What the options are laid over, for their help.
enum class SettingsBase {
  kDefaults,  // evaluate: the defaults (or a settings file), shown as such
  kStored,    // process: the run's stored settings, else the defaults
};

// --method, --window, --step, --passes, --max-shift, --adaptive-refinement,
// --adaptive-threshold, --preprocess, --mask, --roi.
void add_evaluator_options(CLI::App& cmd, EvaluatorArguments& args, SettingsBase base);
// --first-window, --flow, --dis-preset, --subpixel, --interpolator.
void add_evaluation_choices(CLI::App& cmd, EvaluatorArguments& args);

// The given options; throws CLI::ValidationError for a malformed --roi.
pipeline::SettingsOverrides settings_overrides(const EvaluatorArguments& args);
// The choices the stored settings have no key for, applied to `options`.
void apply_evaluation_choices(const EvaluatorArguments& args, fusion::EvaluatorOptions& options);

// `text` as x,y,width,height; throws CLI::ValidationError naming `option`.
cv::Rect parse_roi(const std::string& text, const std::string& option = "--roi");

// A --probe point x,y in pixels; a point off the image is a typing error,
// not a probe to flag: throws CLI::ValidationError saying so.
cv::Point2d parse_probe(const std::string& text, cv::Size image_size);

}  // namespace bosfuse::app
