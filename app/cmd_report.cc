// bosfuse report: the cooling-curve report of a run — one self-contained
// HTML page plus every figure as PNG and SVG and the data as CSV and JSON
// (report/report.h), from the run's samples and what `bosfuse process`
// stored (report/run_input.h): it never evaluates or fits on its own.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <sstream>

#include "app/command.h"
#include "app/output_stream.h"
#include "app/run_argument.h"
#include "report/report.h"
#include "report/run_input.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct ReportArgs {
  std::string run;
  std::string out;
  std::string map_times = "10,60";
  std::string title;
  double contour_px = 0.05;
  double contour_c = 1.0;
  double px_per_mm = 0;
};

std::vector<double> parse_times(const std::string& text) {
  std::vector<double> times;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    std::size_t used = 0;
    double t = 0;
    try {
      t = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || !std::isfinite(t)) {
      throw std::runtime_error(fmt::format("--map-times '{}': '{}' is not a time in seconds", text, item));
    }
    times.push_back(t);
  }
  return times;
}

void make_report(const ReportArgs& args) {
  refuse_standard_output(args.out, "--out", "a report is a folder of files (report.html, figures, CSV, JSON)");
  check_output(args.out, "--out");
  const auto store = storage::RunStore::open(args.run);
  report::RunReportOptions input_options;
  input_options.map_times_s = parse_times(args.map_times);
  if (args.px_per_mm > 0) input_options.px_per_mm = args.px_per_mm;
  const auto input = report::build_report_input(store, input_options);

  report::ReportOptions options;
  options.title = args.title;
  options.displacement_contour_px = args.contour_px;
  options.temperature_contour_c = args.contour_c;
  spdlog::info("drawing the figures and writing {} ...", args.out);
  const auto files = report::write_report(input, options, args.out);
  for (const auto& s : input.series) {
    if (s.fit && s.fit->ok()) {
      std::cerr << fmt::format("{}: k = {:.5g} 1/s [{:.5g}, {:.5g}], tau = {:.4g} s\n", s.name, s.fit->k_per_s.value,
                               s.fit->k_per_s.low, s.fit->k_per_s.high, s.fit->tau_s.value);
    } else {
      std::cerr << fmt::format("{}: no fit ({})\n", s.name, s.fit ? s.fit->summary.message : "not fitted");
    }
  }
  std::cerr << fmt::format("wrote {} figures (PNG and SVG), {} CSV files and {}\n", files.figures.size(),
                           files.csv.size(), files.json.string());
  std::cerr << "report: " << files.html.string() << "\n";
}

void add_report(CLI::App& root) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* cmd = root.add_subcommand(
      "report", "Cooling-curve report of a run: self-contained HTML, figures as PNG/SVG, data as CSV/JSON");
  cmd->add_option("run", args->run, "Run folder (holding run.sqlite)")->required()->transform(run_folder_argument());
  cmd->add_option("--out,-o", args->out, "Folder to write the report into (created if needed)")->required();
  cmd->add_option("--map-times", args->map_times,
                  "Times of the maps, experiment seconds, comma-separated (the nearest frame with a stored field)")
      ->capture_default_str();
  cmd->add_option("--contour", args->contour_px, "Contour spacing of displacement maps, px (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--temperature-contour", args->contour_c, "Contour spacing of temperature maps, °C (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--px-per-mm", args->px_per_mm,
                  "Image scale, px per mm: map axes in mm (default: the run's stored geometry, else axes in px)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--title", args->title, "Title of the report (default: Cooling report — <run name>)");
  cmd->callback([args] { make_report(*args); });
}

BOSFUSE_COMMAND(add_report);

}  // namespace
}  // namespace bosfuse::app
