// bosfuse quality: the image quality index of a captured background against
// the digital pattern it was printed from (Q_L, Q_C, Q_mod, Wang–Bovik Q),
// and a verdict (fusion/scene_match.h): good, usable, poor, not the same
// scene, or no texture, with the number that decided it and its threshold.
// The result is text on standard output; --json FILE writes it for programs
// as well, and --json - puts the JSON alone on standard output (the text
// then goes to standard error).

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "app/command.h"
#include "app/output_stream.h"
#include "fusion/image_quality.h"
#include "fusion/scene_match.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/image_io.h"
#include "pipeline/quality_json.h"
#include "report/figures.h"

namespace bosfuse::app {
namespace {

using pipeline::read_image;

struct QualityArgs {
  std::string image, reference, map, json;
  int window_px = 8;
};

nlohmann::ordered_json quality_json(const QualityArgs& args, const fusion::QualityReport& report,
                                    const fusion::SceneMatch& scene) {
  nlohmann::ordered_json j = {{"image", args.image}, {"reference", args.reference}};
  j.update(pipeline::to_json(report.global));
  j.update(pipeline::to_json(scene));
  j["universal_index"] = report.universal_index;
  j["mean_local_q_mod"] = report.mean_local_q_mod;
  j["window_px"] = args.window_px;
  return j;
}

std::string quality_text(const QualityArgs& args, const fusion::QualityReport& report,
                         const fusion::SceneMatch& scene) {
  const auto& g = report.global;
  return fmt::format(
      "Q_L   {:.3f}  (luminance: mean {:.3f} vs {:.3f} of full scale)\n"
      "Q_C   {:.3f}  (contrast: std {:.3f} vs {:.3f})\n"
      "Q_mod {:.3f}\n"
      "Wang-Bovik Q {:.3f}, mean local Q_mod {:.3f} ({} px windows)\n"
      "verdict: {}\n",
      g.q_l, g.mean_image, g.mean_reference, g.q_c, g.std_image, g.std_reference, g.q_mod, report.universal_index,
      report.mean_local_q_mod, args.window_px, scene.Describe());
}

// The local Q_mod as a map, one cell per window position (a large image's
// map averaged down to at most 400 cells across, which a figure can show).
void write_local_map(const fusion::QualityReport& report, const QualityArgs& args) {
  report::MapField map;
  map.quantity = "local Q_mod";
  map.unit = "";
  const double shrink = std::min(1.0, 400.0 / report.local_q_mod.cols);
  cv::resize(report.local_q_mod, map.values, cv::Size(), shrink, shrink, cv::INTER_AREA);
  map.step_px = 1.0 / shrink;
  map.x0_px = map.y0_px = (args.window_px - 1) / 2.0 + (map.step_px - 1) / 2.0;
  map.source = args.image + " against " + args.reference + fmt::format(", {} px windows", args.window_px);
  report::write_map_figure(map, 0.1, {}, std::nullopt, {900, 650}, report::figure_base(args.map));
}

void quality(const QualityArgs& args) {
  if (!args.map.empty()) {
    refuse_standard_output(args.map, "--map", "the image format comes from the file name (.png)");
    check_figure_output(args.map, "--map");
  }
  check_output(args.json, "--json");
  const cv::Mat image = read_image(args.image, "image");
  const cv::Mat reference = read_image(args.reference, "reference");
  std::optional<OutputStream> json;
  if (!args.json.empty()) json.emplace(args.json, "--json");
  fusion::QualityOptions options;
  options.window_px = args.window_px;
  const auto report = fusion::assess_quality(image, reference, options);
  pipeline::log_warnings(report.warnings);
  const auto scene = fusion::match_scene(image, reference);
  pipeline::log_warnings(scene.warnings);
  text_stream(names_standard_output(args.json)) << quality_text(args, report, scene) << std::flush;
  if (json) {
    json->stream() << quality_json(args, report, scene).dump(2) << "\n";
    json->close();
  }
  if (!args.map.empty()) write_local_map(report, args);
}

void add_quality(CLI::App& root) {
  auto args = std::make_shared<QualityArgs>();
  CLI::App* cmd = root.add_subcommand("quality", "Image quality index of a captured background (Q_L, Q_C, Q_mod) and its verdict: good, usable, poor, "
      "not the same scene, or no texture");
  cmd->add_option("image", args->image, "Captured background image")->required();
  cmd->add_option("--reference", args->reference, "The digital pattern it was printed from")->required();
  cmd->add_option("--json", args->json,
                  "Also write the result as JSON to this file; '-': the JSON alone on standard output (the text "
                  "then goes to standard error)");
  cmd->add_option("--map", args->map, "Write the local Q_mod map to this PNG");
  cmd->add_option("--window", args->window_px, "Sliding window of the local index, px")->capture_default_str();
  cmd->callback([args] { quality(*args); });
}

BOSFUSE_COMMAND(add_quality);

}  // namespace
}  // namespace bosfuse::app
