// bosfuse fit: Newton's law of cooling fitted to a time and a temperature
// column of a plain CSV file (for example one written by `bosfuse export
// --csv`, or piped from it with FILE "-"), so the fitter is useful without
// a run store. Prints the fit and its diagnostics; --json FILE writes them
// for other tools, and --json - puts the JSON alone on standard output (the
// printed fit then goes to standard error). A fit that cannot be trusted is
// an error (exit status 1) with its reason, and the JSON says so.

#include <glog/logging.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>

#include "app/command.h"
#include "app/output_stream.h"
#include "fitting/newton_fit.h"
#include "report/csv_fit.h"

namespace bosfuse::app {
namespace {

using fitting::NewtonFit;
using fitting::NewtonFitOptions;
using report::CsvSeries;

struct FitArgs {
  std::string file;
  std::string time_column;
  std::string temperature_column;
  std::string ambient = "free";
  std::string loss = "none";
  std::optional<double> sigma_c;
  double confidence = 0.95;
  std::string json;
};

NewtonFitOptions fit_options(const FitArgs& args) {
  NewtonFitOptions options;
  options.ambient = report::parse_ambient(args.ambient, "--ambient");
  options.loss = report::parse_loss(args.loss, "--loss");
  options.measurement_sigma_c = args.sigma_c;
  options.confidence = args.confidence;
  if (auto reason = options.Validate(); !reason.empty()) throw std::runtime_error(reason);
  return options;
}

void run_fit(const FitArgs& args) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres logs rank deficiency itself; the summary says it better
  const NewtonFitOptions options = fit_options(args);
  if (!args.json.empty()) check_output(args.json, "--json");
  std::ifstream file;
  if (args.file != "-") {
    file.open(args.file);
    if (!file) throw std::runtime_error("cannot read '" + args.file + "'");
  }
  const CsvSeries series =
      report::read_csv_series(args.file == "-" ? std::cin : file, args.time_column, args.temperature_column);
  const NewtonFit fit = fitting::fit_newton(series.time_s, series.temperature_c, report::with_csv_origin(options, series));
  std::ostream& text = text_stream(names_standard_output(args.json));
  report::print_csv_fit_header(text, series, args.file, fit.origin_s);
  text << fit.brief_report() << std::flush;
  if (!args.json.empty()) {
    OutputStream out(args.json, "--json");
    out.stream() << report::csv_fit_json(fit, series, args.file).dump(2) << "\n";
    out.close();
  }
  if (!fit.ok()) throw std::runtime_error("no fit: " + fit.summary.message);
}

void add_fit(CLI::App& root) {
  auto args = std::make_shared<FitArgs>();
  CLI::App* cmd = root.add_subcommand(
      "fit", "Fit Newton's law of cooling, T = T_amb + (T0 - T_amb) exp(-k t), to a time and a temperature column");
  cmd->add_option("data", args->file,
                  "CSV file with a header row (e.g. from `bosfuse export --csv`); '-': standard input")
      ->required();
  cmd->add_option("--time-column", args->time_column,
                  "Time column: seconds or ISO-8601 UTC (default: t_s, time_s, t, time or time_utc, else the first)");
  cmd->add_option("--temperature-column", args->temperature_column,
                  "Temperature column in °C (default: T, T_c, temperature_c, or the only other column)");
  cmd->add_option("--ambient", args->ambient, "free | fixed:VALUE | prior:VALUE,SIGMA (°C)")->capture_default_str();
  cmd->add_option("--loss", args->loss, "none | huber:SCALE | cauchy:SCALE (°C): robust loss against outliers")
      ->capture_default_str();
  cmd->add_option("--sigma", args->sigma_c,
                  "Known measurement σ in °C: absolute uncertainties and a reduced χ² (default: scaled by the "
                  "residual variance)");
  cmd->add_option("--confidence", args->confidence, "Confidence level of the intervals")->capture_default_str();
  cmd->add_option("--json", args->json,
                  "Also write the fit as JSON to this file; '-': the JSON alone on standard output (the printed fit "
                  "then goes to standard error)");
  cmd->callback([args] { run_fit(*args); });
}

BOSFUSE_COMMAND(add_fit);

}  // namespace
}  // namespace bosfuse::app
