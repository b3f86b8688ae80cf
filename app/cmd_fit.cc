// bosfuse fit: Newton's law of cooling fitted to a time and a temperature
// column of a plain CSV file (for example one written by `bosfuse export
// --csv`, or piped from it with FILE "-"), so the fitter is useful without
// a run store. Prints the fit and its diagnostics; --json FILE writes them
// for other tools, and --json - puts the JSON alone on standard output (the
// printed fit then goes to standard error). A fit that cannot be trusted is
// an error (exit status 1) with its reason, and the JSON says so.

#include <glog/logging.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "acquisition/clock.h"
#include "app/command.h"
#include "app/output_stream.h"
#include "fitting/fit_json.h"
#include "fitting/newton_fit.h"
#include "report/csv_cell.h"

namespace bosfuse::app {
namespace {

using fitting::AmbientModel;
using fitting::NewtonFit;
using fitting::NewtonFitOptions;
using fitting::RobustLoss;

constexpr std::size_t kMaxRows = 100'000'000;  // a bound on the read loop, far above any real record

// Splits one CSV line, honouring double quotes ("a,b" and "" inside them).
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);  // accepts nan and inf, which the fitter rejects and counts
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

// ISO-8601 UTC as `bosfuse export --csv` writes it, 2026-11-23T09:13:48.289123Z
// (a space for the T, no fraction, or +00:00 for the Z are accepted too).
std::optional<std::int64_t> parse_iso8601_utc_ns(const std::string& text) {
  int year, month, day, hour, minute, second, consumed = 0;
  char separator;
  if (std::sscanf(text.c_str(), "%4d-%2d-%2d%c%2d:%2d:%2d%n", &year, &month, &day, &separator, &hour, &minute, &second,
                  &consumed) != 7 ||
      (separator != 'T' && separator != ' ')) {
    return std::nullopt;
  }
  std::size_t i = static_cast<std::size_t>(consumed);
  std::int64_t fraction_ns = 0;
  if (i < text.size() && text[i] == '.') {
    std::int64_t scale = 100'000'000;
    for (++i; i < text.size() && std::isdigit(static_cast<unsigned char>(text[i])); ++i, scale /= 10) {
      fraction_ns += (text[i] - '0') * scale;
    }
  }
  const std::string zone = text.substr(i);
  if (zone != "Z" && zone != "+00:00") return std::nullopt;
  // timegm would quietly roll 2026-13-45 into 2027; a typo must not become a time.
  if (!acquisition::plausible_year(year) || month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 ||
      minute > 59 || second > 60)
    return std::nullopt;
  std::tm fields{};
  fields.tm_year = year - 1900;
  fields.tm_mon = month - 1;
  fields.tm_mday = day;
  fields.tm_hour = hour;
  fields.tm_min = minute;
  fields.tm_sec = second;
  return static_cast<std::int64_t>(timegm(&fields)) * 1'000'000'000 + fraction_ns;
}

struct Columns {
  std::size_t time = 0;
  std::size_t temperature = 0;
};

std::optional<std::size_t> find_column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return i;
  }
  return std::nullopt;
}

std::string list_columns(const std::vector<std::string>& names) {
  std::string text;
  for (const auto& n : names) text += (text.empty() ? "'" : ", '") + n + "'";
  return text;
}

std::size_t choose_time_column(const std::vector<std::string>& header, const std::string& requested) {
  if (!requested.empty()) {
    if (auto i = find_column(header, requested)) return *i;
    throw std::runtime_error("no time column '" + requested + "'; the columns are " + list_columns(header));
  }
  for (const char* name : {"t_s", "time_s", "t", "time", "time_utc"}) {
    if (auto i = find_column(header, name)) return *i;
  }
  return 0;
}

std::size_t choose_temperature_column(const std::vector<std::string>& header, const std::string& requested,
                                      std::size_t time_column) {
  if (!requested.empty()) {
    if (auto i = find_column(header, requested)) return *i;
    throw std::runtime_error("no temperature column '" + requested + "'; the columns are " + list_columns(header));
  }
  for (const char* name : {"T", "T_c", "temperature_c", "temperature"}) {
    if (auto i = find_column(header, name)) return *i;
  }
  std::vector<std::string> candidates;
  std::size_t chosen = 0;
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (i == time_column || header[i] == "t_s" || header[i] == "time_utc") continue;
    candidates.push_back(header[i]);
    chosen = i;
  }
  if (candidates.size() == 1) return chosen;
  if (candidates.empty()) throw std::runtime_error("the file has no temperature column");
  throw std::runtime_error("several temperature columns (" + list_columns(candidates) +
                           "): choose one with --temperature-column");
}

// The two columns as numbers: times in seconds, relative to the earliest
// ISO-8601 time when the column holds such times (subtracted in integer
// nanoseconds, so no precision is lost to epoch-scale doubles).
struct CsvSeries {
  std::string time_name;
  std::string temperature_name;
  std::vector<double> time_s;
  std::vector<double> temperature_c;
  std::optional<std::int64_t> iso_origin_ns;
  std::size_t empty_rows = 0;  // rows with an empty time or temperature cell (not a measurement)
};

struct TimeCell {
  std::optional<double> seconds;
  std::optional<std::int64_t> iso_ns;
};

TimeCell parse_time_cell(const std::string& text, std::size_t line_number) {
  if (auto seconds = parse_number(text)) return {seconds, std::nullopt};
  if (auto ns = parse_iso8601_utc_ns(text)) return {std::nullopt, ns};
  throw std::runtime_error("line " + std::to_string(line_number) + ": time '" + text +
                           "' is neither seconds nor ISO-8601 UTC (2026-11-23T09:13:48.289Z)");
}

CsvSeries read_series(std::istream& in, const std::string& time_column, const std::string& temperature_column) {
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error("the file is empty");
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // the UTF-8 byte order mark spreadsheets write
  // Names as written, without the quote that neutralised a formula-like one.
  std::vector<std::string> header;
  for (const auto& cell : split_csv_line(line)) header.push_back(report::csv_text_from_cell(cell));
  CsvSeries series;
  const Columns columns{choose_time_column(header, time_column),
                        choose_temperature_column(header, temperature_column, choose_time_column(header, time_column))};
  series.time_name = header[columns.time];
  series.temperature_name = header[columns.temperature];
  std::vector<std::int64_t> iso_ns;
  std::optional<bool> iso_times;  // decided by the first row
  std::size_t line_number = 1;
  for (std::size_t row = 0; row < kMaxRows && std::getline(in, line); ++row) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv_line(line);
    const std::string time_text = columns.time < cells.size() ? cells[columns.time] : "";
    const std::string value_text = columns.temperature < cells.size() ? cells[columns.temperature] : "";
    if (time_text.empty() || value_text.empty()) {
      ++series.empty_rows;
      continue;
    }
    const auto value = parse_number(value_text);
    if (!value) {
      throw std::runtime_error("line " + std::to_string(line_number) + ": temperature '" + value_text +
                               "' is not a number");
    }
    const TimeCell time = parse_time_cell(time_text, line_number);
    if (!iso_times) iso_times = time.iso_ns.has_value();
    if (*iso_times != time.iso_ns.has_value()) {
      throw std::runtime_error("line " + std::to_string(line_number) + ": the time column mixes seconds and ISO-8601");
    }
    if (time.iso_ns) iso_ns.push_back(*time.iso_ns);
    series.time_s.push_back(time.seconds.value_or(0.0));
    series.temperature_c.push_back(*value);
  }
  if (!iso_ns.empty()) {
    series.iso_origin_ns = *std::min_element(iso_ns.begin(), iso_ns.end());
    for (std::size_t i = 0; i < iso_ns.size(); ++i) {
      series.time_s[i] = static_cast<double>(iso_ns[i] - *series.iso_origin_ns) * 1e-9;
    }
  }
  return series;
}

AmbientModel parse_ambient(const std::string& text) {
  if (text == "free") return AmbientModel::free();
  if (text.rfind("fixed:", 0) == 0) {
    if (auto v = parse_number(text.substr(6)); v && std::isfinite(*v)) return AmbientModel::fixed(*v);
  }
  if (text.rfind("prior:", 0) == 0) {
    const auto comma = text.find(',');
    const auto v = parse_number(text.substr(6, comma == std::string::npos ? std::string::npos : comma - 6));
    const auto s = comma == std::string::npos ? std::nullopt : parse_number(text.substr(comma + 1));
    if (v && s) return AmbientModel::prior(*v, *s);
  }
  throw std::runtime_error("--ambient '" + text + "': expected free, fixed:VALUE or prior:VALUE,SIGMA (°C)");
}

RobustLoss parse_loss(const std::string& text) {
  if (text == "none") return RobustLoss::none();
  const auto colon = text.find(':');
  const auto scale = colon == std::string::npos ? std::nullopt : parse_number(text.substr(colon + 1));
  if (scale && text.substr(0, colon) == "huber") return RobustLoss::huber(*scale);
  if (scale && text.substr(0, colon) == "cauchy") return RobustLoss::cauchy(*scale);
  throw std::runtime_error("--loss '" + text + "': expected none, huber:SCALE or cauchy:SCALE (°C)");
}

// The shared fit layout plus where the data came from.
nlohmann::ordered_json fit_json(const NewtonFit& fit, const CsvSeries& series, const std::string& file) {
  nlohmann::ordered_json j = fitting::to_json(fit);
  j["input"] = {{"file", file}, {"time_column", series.time_name}, {"temperature_column", series.temperature_name}};
  if (series.iso_origin_ns) j["origin_time_utc"] = acquisition::format_iso8601_utc(*series.iso_origin_ns, 6);
  j["diagnostics"]["empty_rows_skipped"] = series.empty_rows;
  return j;
}

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
  options.ambient = parse_ambient(args.ambient);
  options.loss = parse_loss(args.loss);
  options.measurement_sigma_c = args.sigma_c;
  options.confidence = args.confidence;
  if (auto reason = options.invalid_reason(); !reason.empty()) throw std::runtime_error(reason);
  return options;
}

void print_header(std::ostream& out, const CsvSeries& series, const std::string& file, double origin_s) {
  out << (file == "-" ? "standard input" : file) << ": '" << series.temperature_name << "' against '"
      << series.time_name << "'";
  if (series.iso_origin_ns) {
    out << " (t = 0 at " << acquisition::format_iso8601_utc(*series.iso_origin_ns, 6) << ")";
  } else if (origin_s != 0.0) {
    out << " (t = 0 at " << series.time_name << " = " << std::setprecision(15) << origin_s << std::setprecision(6)
        << ")";
  }
  if (series.empty_rows) out << "; " << series.empty_rows << " rows with an empty cell skipped";
  out << "\n";
}

void run_fit(const FitArgs& args) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres logs rank deficiency itself; the summary says it better
  const NewtonFitOptions options = fit_options(args);
  std::ifstream file;
  if (args.file != "-") {
    file.open(args.file);
    if (!file) throw std::runtime_error("cannot read '" + args.file + "'");
  }
  const CsvSeries series = read_series(args.file == "-" ? std::cin : file, args.time_column, args.temperature_column);
  const NewtonFit fit = fitting::fit_newton(series.time_s, series.temperature_c, options);
  std::ostream& text = text_stream(names_standard_output(args.json));
  print_header(text, series, args.file, fit.origin_s);
  text << fit.brief_report() << std::flush;
  if (!args.json.empty()) {
    OutputStream out(args.json);
    out.stream() << fit_json(fit, series, args.file).dump(2) << "\n";
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
