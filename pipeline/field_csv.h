#pragma once
// A field file (docs/SCHEMA.md, table `fields`): a displacement or
// temperature field (fusion/displacement_field.h, fusion/temperature_field.h)
// written as CSV by write_csv() and read back onto its grid: displacement
// `x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v` or temperature
// `x,y,temperature_c,measured,sigma_c`, one line per grid node. Processing
// and `bosfuse evaluate` write through it; the writers and this one reader
// share the column names below, so the layout cannot drift between them;
// the report's maps and the HDF5 export read through it. It lives here, not
// in fusion/, because fusion/ opens no files.
//
// The grid is whatever distinct x and y values the file holds (ascending),
// so it needs no step to be declared and a file with missing nodes still
// reads: such nodes are NaN in every column and 0 in `present`. Empty cells
// (a temperature the field could not give) are NaN too.

#include <filesystem>
#include <iosfwd>
#include <opencv2/core.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::fusion {
struct DisplacementField;
struct TemperatureField;
}  // namespace bosfuse::fusion

namespace bosfuse::pipeline {

struct StoredFieldGrid {
  std::vector<double> x_px;          // column positions, ascending (image coordinates, DESIGN.md)
  std::vector<double> y_px;          // row positions, ascending (y down)
  std::vector<std::string> columns;  // the value columns after x,y, in file order
  std::vector<cv::Mat> values;       // per column: CV_64F, y_px.size() × x_px.size()
  cv::Mat present;                   // CV_8U of the same size, 1 where the file has the node

  int rows() const { return static_cast<int>(y_px.size()); }
  int cols() const { return static_cast<int>(x_px.size()); }
  // The values of column `name`; throws std::out_of_range naming it when absent.
  const cv::Mat& column(std::string_view name) const;
};

// `flag` holds the flag's name (displacement_field.h: ok, no-peak,
// beyond-search, ...); it is read as the flag's value.
inline constexpr std::string_view kDisplacementColumns[] = {"u",          "v",       "valid",  "flag",
                                                            "peak_ratio", "sigma_u", "sigma_v"};
inline constexpr std::string_view kTemperatureColumns[] = {"temperature_c", "measured", "sigma_c"};
// Columns a field file written before they existed lacks (σ came with
// issue 29, at the end; flag with issue 30, after valid): such a file still
// reads, these columns NaN.
inline constexpr std::string_view kColumnsAddedLater[] = {"flag", "sigma_u", "sigma_v", "sigma_c"};

// The header line of a field file with these value columns ("x,y,u,v,...").
std::string field_csv_header(std::span<const std::string_view> value_columns);

// Builds a field file's text, the header and then a line per node, in one
// buffer: a 16 MP field has 250 k lines, and a stream insertion per line
// costs more than the formatting. Numbers are std::to_chars in fixed point
// (shortest round trip of the rounded value, as printf's "%.Nf" prints it),
// about twice as fast as fmt's fixed format here.
class FieldCsvWriter {
 public:
  FieldCsvWriter(std::span<const std::string_view> value_columns, std::size_t nodes);

  void fixed(double value, int decimals);  // a cell: "nan", "inf" for those
  void integer(int value);                 // a cell
  void text(std::string_view value);       // a cell, as it is (no comma in it)
  void empty();                            // a cell with nothing in it
  void end_line();

  std::string_view text() const { return text_; }
  // Writes the text to `path`; throws std::runtime_error naming it.
  void save(const std::filesystem::path& path) const;

 private:
  std::string text_;
};

// Reads `path`, whose header must be `x,y` followed by `value_columns` in
// order, less any of kColumnsAddedLater (then NaN).
// Throws std::runtime_error naming the file (and the line) when it cannot be
// read, has another header, a short line or a cell that is not a number, or
// holds no node.
StoredFieldGrid read_stored_field(const std::filesystem::path& path, std::span<const std::string_view> value_columns);

// CSV with the header `x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v`, one
// vector per line (flag by its name, σ 0 where not estimated).
void write_csv(const fusion::DisplacementField& field, std::ostream& out);
void write_csv(const fusion::DisplacementField& field, const std::filesystem::path& path);

// CSV with the header `x,y,temperature_c,measured,sigma_c`; NaN written as
// `nan`, the `measured` flag saying whether the node's value is a
// measurement's.
void write_csv(const fusion::TemperatureField& field, const std::filesystem::path& path);

}  // namespace bosfuse::pipeline
