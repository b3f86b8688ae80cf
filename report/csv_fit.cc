#include "report/csv_fit.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <stdexcept>

#include "acquisition/clock.h"
#include "fitting/fit_json.h"

namespace bosfuse::report {

fitting::AmbientModel parse_ambient(const std::string& text, const std::string& option) {
  using fitting::AmbientModel;
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
  throw std::runtime_error(option + " '" + text + "': expected free, fixed:VALUE or prior:VALUE,SIGMA (°C)");
}

fitting::RobustLoss parse_loss(const std::string& text, const std::string& option) {
  using fitting::RobustLoss;
  if (text == "none") return RobustLoss::none();
  const auto colon = text.find(':');
  const auto scale = colon == std::string::npos ? std::nullopt : parse_number(text.substr(colon + 1));
  if (scale && text.substr(0, colon) == "huber") return RobustLoss::huber(*scale);
  if (scale && text.substr(0, colon) == "cauchy") return RobustLoss::cauchy(*scale);
  throw std::runtime_error(option + " '" + text + "': expected none, huber:SCALE or cauchy:SCALE (°C)");
}

fitting::NewtonFitOptions with_csv_origin(fitting::NewtonFitOptions options, const CsvSeries& series) {
  constexpr double kYear_s = 365.25 * 86400;
  double earliest = INFINITY;
  for (double t : series.time_s) {
    if (std::isfinite(t)) earliest = std::min(earliest, t);
  }
  if (std::abs(earliest) < kYear_s) options.origin_s = 0.0;
  return options;
}

void print_csv_fit_header(std::ostream& out, const CsvSeries& series, const std::string& file, double origin_s) {
  out << (file == "-" ? "standard input" : file) << ": '" << series.temperature_name << "' against '"
      << series.time_name << "'";
  if (series.iso_origin_ns) {
    out << " (t = 0 at " << acquisition::format_iso8601_utc(*series.iso_origin_ns, 6);
    if (series.time_scale && *series.time_scale != 1) {
      out << "; experiment seconds: the recorded times × " << *series.time_scale << ", the file's time_scale";
    }
    out << ")";
  } else if (origin_s != 0.0) {
    out << " (t = 0 at " << series.time_name << " = " << std::setprecision(15) << origin_s << std::setprecision(6)
        << ")";
  }
  if (series.empty_rows) out << "; " << series.empty_rows << " rows with an empty cell skipped";
  out << "\n";
}

nlohmann::ordered_json csv_fit_json(const fitting::NewtonFit& fit, const CsvSeries& series, const std::string& file) {
  nlohmann::ordered_json j = fitting::to_json(fit);
  j["input"] = {{"file", file}, {"time_column", series.time_name}, {"temperature_column", series.temperature_name}};
  if (series.time_scale) j["input"]["time_scale"] = *series.time_scale;
  if (series.iso_origin_ns) j["origin_time_utc"] = acquisition::format_iso8601_utc(*series.iso_origin_ns, 6);
  j["diagnostics"]["empty_rows_skipped"] = series.empty_rows;
  return j;
}

}  // namespace bosfuse::report
