#include "pipeline/field_csv.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <stdexcept>

#include "fusion/displacement_field.h"
#include "fusion/temperature_field.h"

namespace bosfuse::pipeline {
namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

// from_chars rather than stod: it ignores the locale and rejects trailing text.
bool parse_number(std::string_view cell, double& out) {
  if (cell.empty()) {
    out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  const auto [end, error] = std::from_chars(cell.data(), cell.data() + cell.size(), out);
  return error == std::errc() && end == cell.data() + cell.size();
}

}  // namespace

const cv::Mat& StoredFieldGrid::column(std::string_view name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw std::out_of_range(fmt::format("the field has no column '{}'", name));
  return values[static_cast<std::size_t>(it - columns.begin())];
}

std::string field_csv_header(std::span<const std::string_view> value_columns) {
  std::string header = "x,y";
  for (const auto column : value_columns) {
    header += ',';
    header += column;
  }
  return header;
}

FieldCsvWriter::FieldCsvWriter(std::span<const std::string_view> value_columns, std::size_t nodes) {
  text_.reserve(64 * (nodes + 1));
  text_ += field_csv_header(value_columns);
  text_ += '\n';
}

namespace {

// `value` rounded to `decimals` places as an integer count of 10^−decimals,
// when one product in double decides it: the product is within half an ulp
// of the exact value·10^decimals, so unless that lies within an ulp of a
// half-way point (or of 2^53), both round to the same integer. Ties and
// other close calls are left to the exact formatter (false).
bool scaled_integer(double value, int decimals, std::int64_t& out) {
  static constexpr double kPowers[] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  constexpr double kLimit = 1e15;  // well below 2^53: ulps of at most 1/8
  if (decimals < 0 || decimals > 9) return false;
  const double scaled = std::abs(value) * kPowers[decimals];
  if (!(scaled < kLimit)) return false;  // also NaN
  const double below = std::floor(scaled);
  const double past_half = scaled - below - 0.5;
  if (std::abs(past_half) <= 2 * std::numeric_limits<double>::epsilon() * scaled) return false;
  out = static_cast<std::int64_t>(below) + (past_half > 0 ? 1 : 0);
  return true;
}

}  // namespace

void FieldCsvWriter::fixed(double value, int decimals) {
  // The exact formatter (std::to_chars, Ryu's fixed printf) costs about half
  // a 16 MP field file's time; most cells are decided by one product and an
  // integer conversion, which print the same characters.
  std::int64_t units = 0;
  if (scaled_integer(value, decimals, units)) {
    // The digits with zeros in front up to one before the point: 0.0012 is 12 units of 1e−4.
    char digits[32];
    char* const first = digits + 10;
    const int count = static_cast<int>(std::to_chars(first, digits + sizeof digits, units).ptr - first);
    const int padding = std::max(decimals + 1 - count, 0);
    std::fill(first - padding, first, '0');
    const std::string_view padded(first - padding, static_cast<std::size_t>(count + padding));
    if (std::signbit(value)) text_ += '-';
    text_ += padded.substr(0, padded.size() - static_cast<std::size_t>(decimals));
    if (decimals > 0) {
      text_ += '.';
      text_ += padded.substr(padded.size() - static_cast<std::size_t>(decimals));
    }
    text_ += ',';
    return;
  }
  // Room for the widest fixed double: 309 digits, sign, point and decimals.
  char cell[400];
  const auto [end, error] = std::to_chars(cell, cell + sizeof cell, value, std::chars_format::fixed, decimals);
  if (error != std::errc()) throw std::logic_error("a field value does not fit its cell");
  text_.append(cell, end);
  text_ += ',';
}

void FieldCsvWriter::integer(int value) {
  char cell[16];
  text_.append(cell, std::to_chars(cell, cell + sizeof cell, value).ptr);
  text_ += ',';
}

void FieldCsvWriter::text(std::string_view value) {
  text_ += value;
  text_ += ',';
}

void FieldCsvWriter::empty() { text_ += ','; }

void FieldCsvWriter::end_line() {
  if (!text_.empty() && text_.back() == ',') text_.back() = '\n';
}

void FieldCsvWriter::save(const std::filesystem::path& path) const {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error(path.string() + ": cannot open for writing");
  out.write(text_.data(), static_cast<std::streamsize>(text_.size()));
  if (!out.flush()) throw std::runtime_error(path.string() + ": write failed");
}

namespace {

bool added_later(std::string_view column) {
  return std::find(std::begin(kColumnsAddedLater), std::end(kColumnsAddedLater), column) !=
         std::end(kColumnsAddedLater);
}

// Where each of the header's value columns lies in `value_columns`: all of
// them in order, less any of kColumnsAddedLater; empty when it is not such
// a header.
std::vector<std::size_t> column_positions(const std::string& header, std::span<const std::string_view> value_columns) {
  const auto names = split(header);
  if (names.size() < 3 || names[0] != "x" || names[1] != "y") return {};
  std::vector<std::size_t> positions;
  std::size_t next = 0;
  for (std::size_t i = 2; i < names.size(); ++i) {
    for (; next < value_columns.size() && value_columns[next] != names[i]; ++next) {
      if (!added_later(value_columns[next])) return {};
    }
    if (next == value_columns.size()) return {};
    positions.push_back(next++);
  }
  for (; next < value_columns.size(); ++next) {
    if (!added_later(value_columns[next])) return {};
  }
  return positions;
}

// A cell of column `name`: a number, or for `flag` a flag's name
// (fusion/displacement_field.h), read as its value.
bool parse_cell(std::string_view name, std::string_view cell, double& out) {
  if (name != "flag") return parse_number(cell, out);
  fusion::VectorFlag flag{};
  if (!fusion::parse_vector_flag(cell, flag)) return false;
  out = static_cast<double>(flag);
  return true;
}

}  // namespace

StoredFieldGrid read_stored_field(const std::filesystem::path& path, std::span<const std::string_view> value_columns) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("cannot read '{}'", path.string()));
  const std::string expected = field_csv_header(value_columns);
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::size_t> positions = column_positions(line, value_columns);
  if (positions.empty()) {
    throw std::runtime_error(
        fmt::format("'{}': the header is '{}', expected '{}'", path.string(), line.substr(0, 80), expected));
  }
  const std::size_t width = positions.size() + 2;
  // Nodes keyed by (y, x) so rows come out in order; the grid is known only at the end.
  std::map<std::pair<double, double>, std::vector<double>> nodes;
  std::size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = split(line);
    if (cells.size() != width) {
      throw std::runtime_error(
          fmt::format("'{}' line {}: {} cells, expected {}", path.string(), line_number, cells.size(), width));
    }
    std::vector<double> numbers(value_columns.size() + 2, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < width; ++i) {
      const std::size_t to = i < 2 ? i : positions[i - 2] + 2;
      const std::string_view name = i < 2 ? std::string_view(i == 0 ? "x" : "y") : value_columns[positions[i - 2]];
      if (!parse_cell(name, cells[i], numbers[to]) || (i < 2 && !std::isfinite(numbers[to]))) {
        throw std::runtime_error(fmt::format("'{}' line {}: '{}' is not a {}", path.string(), line_number,
                                             cells[i].substr(0, 40), name == "flag" ? "flag" : "number"));
      }
    }
    const std::pair key{numbers[1], numbers[0]};
    numbers.erase(numbers.begin(), numbers.begin() + 2);
    if (!nodes.emplace(key, std::move(numbers)).second) {
      throw std::runtime_error(fmt::format("'{}' line {}: the node ({}, {}) appears twice", path.string(), line_number,
                                           key.second, key.first));
    }
  }
  if (nodes.empty()) throw std::runtime_error(fmt::format("'{}' holds no grid", path.string()));

  StoredFieldGrid grid;
  for (const auto& [key, values] : nodes) {
    grid.y_px.push_back(key.first);
    grid.x_px.push_back(key.second);
  }
  for (auto* axis : {&grid.x_px, &grid.y_px}) {
    std::sort(axis->begin(), axis->end());
    axis->erase(std::unique(axis->begin(), axis->end()), axis->end());
  }
  grid.columns.assign(value_columns.begin(), value_columns.end());
  for (std::size_t i = 0; i < value_columns.size(); ++i) {
    grid.values.emplace_back(grid.rows(), grid.cols(), CV_64F, cv::Scalar(std::numeric_limits<double>::quiet_NaN()));
  }
  grid.present = cv::Mat::zeros(grid.rows(), grid.cols(), CV_8U);
  for (const auto& [key, values] : nodes) {
    const int r = static_cast<int>(std::lower_bound(grid.y_px.begin(), grid.y_px.end(), key.first) - grid.y_px.begin());
    const int c =
        static_cast<int>(std::lower_bound(grid.x_px.begin(), grid.x_px.end(), key.second) - grid.x_px.begin());
    grid.present.at<std::uint8_t>(r, c) = 1;
    for (std::size_t i = 0; i < values.size(); ++i) grid.values[i].at<double>(r, c) = values[i];
  }
  return grid;
}

namespace {

FieldCsvWriter field_text(const fusion::DisplacementField& field) {
  FieldCsvWriter csv(kDisplacementColumns, field.vectors.size());
  for (const auto& v : field.vectors) {
    // Enough digits for 0.001 px work; the centre is exact in half pixels.
    csv.fixed(v.x_px, 1);
    csv.fixed(v.y_px, 1);
    csv.fixed(v.u_px, 5);
    csv.fixed(v.v_px, 5);
    csv.integer(v.valid() ? 1 : 0);
    csv.text(to_string(v.flag));
    csv.fixed(v.peak_ratio, 3);
    csv.fixed(v.sigma_u_px, 5);
    csv.fixed(v.sigma_v_px, 5);
    csv.end_line();
  }
  return csv;
}

}  // namespace

void write_csv(const fusion::DisplacementField& field, std::ostream& out) {
  const FieldCsvWriter csv = field_text(field);
  const std::string_view text = csv.text();
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
}

void write_csv(const fusion::DisplacementField& field, const std::filesystem::path& path) {
  field_text(field).save(path);
}

void write_csv(const fusion::TemperatureField& field, const std::filesystem::path& path) {
  FieldCsvWriter csv(kTemperatureColumns, static_cast<std::size_t>(field.rows) * field.cols);
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const std::size_t i = field.index(r, c);
      const double t = field.temperature_c[i];
      csv.fixed(field.x0_px + c * field.step_px, 1);
      csv.fixed(field.y0_px + r * field.step_px, 1);
      csv.fixed(t, 4);  // NaN as "nan"
      csv.integer(int{field.measured[i]});
      csv.fixed(i < field.sigma_c.size() ? field.sigma_c[i] : std::numeric_limits<double>::quiet_NaN(), 5);
      csv.end_line();
    }
  }
  csv.save(path);
}

}  // namespace bosfuse::pipeline
