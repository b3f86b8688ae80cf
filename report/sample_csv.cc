#include "report/sample_csv.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <map>

#include "acquisition/clock.h"
#include "report/csv_cell.h"
#include "storage/experiment_clock.h"
#include "storage/value_digits.h"

namespace bosfuse::report {

std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);  // accepts nan and inf, which the fitter rejects and counts
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

namespace {

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
    if (i == time_column || header[i] == "t_s" || header[i] == "time_utc" || header[i] == kTimeScaleColumn) continue;
    candidates.push_back(header[i]);
    chosen = i;
  }
  if (candidates.size() == 1) return chosen;
  if (candidates.empty()) throw std::runtime_error("the file has no temperature column");
  throw std::runtime_error("several temperature columns (" + list_columns(candidates) +
                           "): choose one with --temperature-column");
}

// The export's time_scale cell of a row: a positive number, the same in
// every row (one run has one scale).
double parse_time_scale_cell(const std::string& text, std::size_t line_number, std::optional<double> earlier) {
  const auto scale = parse_number(text);
  if (!scale || !(*scale > 0) || !std::isfinite(*scale)) {
    throw std::runtime_error("line " + std::to_string(line_number) + ": time_scale '" + text +
                             "' is not a positive number");
  }
  if (earlier && *earlier != *scale) {
    throw std::runtime_error("line " + std::to_string(line_number) + ": time_scale " + text + " differs from " +
                             fmt::format("{}", *earlier) + " above it; a file holds one run's times");
  }
  return *scale;
}

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

}  // namespace

void write_samples_csv(const storage::RunStore& store, std::ostream& out) {
  const auto channels = store.channels();
  std::map<std::int64_t, std::size_t> column;
  std::vector<std::optional<double>> resolution;
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  out << "time_utc,t_s,time_scale";
  for (const auto& c : channels) {
    column[c.id] = column.size();
    resolution.push_back(c.resolution);
    out << "," << csv_text_cell(c.name + " [" + c.unit + "]");
  }
  out << "\n";
  std::vector<std::string> cells(channels.size());
  std::optional<std::int64_t> row_t;
  const auto flush_row = [&] {
    if (!row_t) return;
    out << storage::format_iso8601_utc(*row_t, 6) << "," << fmt::format("{:.6f}", clock.seconds(*row_t)) << ","
        << fmt::format("{}", clock.time_scale);
    for (auto& cell : cells) {
      out << "," << cell;
      cell.clear();
    }
    out << "\n";
  };
  store.for_each_sample([&](const storage::Sample& s) {
    if (row_t != s.t_ns) {
      flush_row();
      row_t = s.t_ns;
    }
    // At the channel's digits (storage/value_digits.h): a quantised reading
    // is 23.4, not 23.400000000000002; run.sqlite keeps the stored double.
    const std::size_t i = column.at(s.channel_id);
    if (s.value) cells[i] = storage::format_channel_value(*s.value, resolution[i]);
  });
  flush_row();
}


CsvSeries read_csv_series(std::istream& in, const std::string& time_column, const std::string& temperature_column) {
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error("the file is empty");
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // the UTF-8 byte order mark spreadsheets write
  // Names as written, without the quote that neutralised a formula-like one.
  std::vector<std::string> header;
  for (const auto& cell : split_csv_line(line)) header.push_back(csv_text_from_cell(cell));
  CsvSeries series;
  const Columns columns{choose_time_column(header, time_column),
                        choose_temperature_column(header, temperature_column, choose_time_column(header, time_column))};
  series.time_name = header[columns.time];
  series.temperature_name = header[columns.temperature];
  std::vector<std::int64_t> iso_ns;
  std::optional<bool> iso_times;  // decided by the first row
  const std::optional<std::size_t> scale_column = find_column(header, kTimeScaleColumn);
  std::size_t line_number = 1;
  for (std::size_t row = 0; row < kMaxRows && std::getline(in, line); ++row) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv_line(line);
    // A row with a cell too many or too few has lost or gained a separator
    // (a comma in an unquoted name, a row cut short): its cells may not be
    // under the header they seem to be, so no value of it can be trusted.
    if (cells.size() != header.size()) {
      throw std::runtime_error("line " + std::to_string(line_number) + ": " + std::to_string(cells.size()) +
                               " cells, but the header has " + std::to_string(header.size()));
    }
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
    if (time.iso_ns && scale_column) {
      series.time_scale = parse_time_scale_cell(cells[*scale_column], line_number, series.time_scale);
    }
    series.time_s.push_back(time.seconds.value_or(0.0));
    series.temperature_c.push_back(*value);
  }
  if (!iso_ns.empty()) {
    series.iso_origin_ns = *std::min_element(iso_ns.begin(), iso_ns.end());
    for (std::size_t i = 0; i < iso_ns.size(); ++i) {
      series.time_s[i] = static_cast<double>(iso_ns[i] - *series.iso_origin_ns) * 1e-9 * series.time_scale.value_or(1);
    }
  }
  return series;
}

}  // namespace bosfuse::report
