#include "pipeline/field_csv.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "fusion/displacement_field.h"
#include "fusion/temperature_field.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

// A field of one row of two vectors.
fusion::DisplacementField row_of_two(const fusion::DisplacementVector& first,
                                     const fusion::DisplacementVector& second) {
  fusion::DisplacementField field;
  field.rows = 1;
  field.cols = 2;
  field.vectors = {first, second};
  return field;
}

// `field` written to a file in `dir` and read back.
StoredFieldGrid written_back(const fusion::DisplacementField& field, const std::filesystem::path& dir) {
  write_csv(field, dir / "d.csv");
  return read_stored_field(dir / "d.csv", kDisplacementColumns);
}

std::string error_of(const std::filesystem::path& path, std::span<const std::string_view> columns) {
  try {
    read_stored_field(path, columns);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// The cells are what C's printf("%.Nf") prints: the exactly rounded value
// (ties of binary fractions to even), nan and inf by name.
TEST(FieldCsvWriter, CellsArePrintfsFixedPoint) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> values = {0.0, -0.0, 0.125, 2.5, -1e-9, 1e300, -123456.789012345, kNaN, -kNaN, kInf, -kInf};
  std::mt19937 random(7);
  std::normal_distribution<double> spread(0.0, 3.0);
  for (int i = 0; i < 2000; ++i) values.push_back(spread(random));
  const std::string_view columns[] = {"a", "b"};
  FieldCsvWriter csv(columns, values.size());
  std::string expected = "x,y,a,b\n";
  char cell[400];
  for (const double value : values) {
    for (const int decimals : {1, 3, 5}) csv.fixed(value, decimals);
    csv.empty();
    csv.integer(-7);
    csv.end_line();
    for (const int decimals : {1, 3, 5}) {
      std::snprintf(cell, sizeof cell, "%.*f,", decimals, value);
      expected += cell;
    }
    expected += ",-7\n";
  }
  EXPECT_EQ(csv.text(), expected);
}

// Most cells are rounded by one product in double; near a half-way point,
// where that product could round the other way, the exact formatter takes
// over. Both must print what printf prints, at every scale and number of
// decimals, ties and their neighbouring doubles included.
TEST(FieldCsvWriter, CellsNearHalfWayPointsArePrintfsToo) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-12, 15), units(0, 1'000'000);
  std::vector<std::pair<double, int>> cells;
  for (int decimals = 0; decimals <= 11; ++decimals) {
    for (int i = 0; i < 3000; ++i) cells.emplace_back(mantissa(random) * std::pow(10.0, exponent(random)), decimals);
    for (int i = 0; i < 1000; ++i) {
      const double tie = (units(random) + 0.5) / std::pow(10.0, decimals);
      for (const double value : {tie, std::nextafter(tie, 0.0), std::nextafter(tie, 1e300), -tie}) {
        cells.emplace_back(value, decimals);
      }
    }
  }
  const std::string_view columns[] = {"a"};
  char expected[400];
  for (const auto& [value, decimals] : cells) {
    FieldCsvWriter csv(columns, 1);
    csv.fixed(value, decimals);
    csv.end_line();
    std::snprintf(expected, sizeof expected, "x,y,a\n%.*f\n", decimals, value);
    ASSERT_EQ(csv.text(), std::string(expected)) << std::hexfloat << value << " to " << decimals << " decimals";
  }
}

TEST(FieldCsvWriter, AFileThatCannotBeWrittenIsNamed) {
  const std::string_view columns[] = {"a"};
  try {
    FieldCsvWriter(columns, 0).save("/nonexistent-folder/field.csv");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-folder/field.csv"), std::string::npos) << e.what();
  }
}

TEST(FieldCsv, ReadsTheGridInRowOrderWhateverTheLineOrder) {
  testing::TempDir dir;
  std::ofstream(dir / "d.csv") << "x,y,u,v,valid,peak_ratio\n"
                               << "16.0,8.0,0.10000,-0.20000,1,2.500\n"
                               << "8.0,8.0,0.30000,0.40000,1,3.000\n"
                               << "8.0,16.0,9.00000,9.00000,0,1.000\n"
                               << "16.0,16.0,0.00000,0.00000,0,0.000\n";
  const auto grid = read_stored_field(dir / "d.csv", kDisplacementColumns);
  EXPECT_EQ(grid.x_px, (std::vector<double>{8, 16}));
  EXPECT_EQ(grid.y_px, (std::vector<double>{8, 16}));
  ASSERT_EQ(grid.columns.size(), 7u);
  // Written before issue 29: no σ columns, read as NaN; before issue 30, no flag.
  EXPECT_TRUE(std::isnan(grid.column("flag").at<double>(0, 0)));
  EXPECT_TRUE(std::isnan(grid.column("sigma_u").at<double>(0, 0)));
  EXPECT_TRUE(std::isnan(grid.column("sigma_v").at<double>(1, 1)));
  EXPECT_EQ(grid.column("u").at<double>(0, 0), 0.3) << "the text's double, exactly";
  EXPECT_EQ(grid.column("v").at<double>(0, 1), -0.2);
  EXPECT_EQ(grid.column("valid").at<double>(1, 0), 0.0);
  EXPECT_EQ(grid.column("peak_ratio").at<double>(0, 1), 2.5);
  EXPECT_EQ(cv::countNonZero(grid.present), 4);
  EXPECT_THROW(grid.column("w"), std::out_of_range);
}

TEST(FieldCsv, ReadsTheUncertaintyColumnsWrittenBack) {
  testing::TempDir dir;
  const auto grid = written_back(row_of_two({7.5, 7.5, 0.25, -1.5, 3.2, fusion::VectorFlag::kOk, false, 0.0123, 0.0045},
                                            {15.5, 7.5, 0, 0, 0, fusion::VectorFlag::kMasked}),
                                 dir.path());
  EXPECT_EQ(grid.column("sigma_u").at<double>(0, 0), 0.0123);
  EXPECT_EQ(grid.column("sigma_v").at<double>(0, 0), 0.0045);
  EXPECT_EQ(grid.column("sigma_u").at<double>(0, 1), 0.0) << "not estimated";
}

TEST(FieldCsv, ReadsTheFlagColumnWrittenBackByName) {
  testing::TempDir dir;
  const auto grid = written_back(row_of_two({7.5, 7.5, 0.25, -1.5, 3.2, fusion::VectorFlag::kOk},
                                            {15.5, 7.5, 0, 0, 0, fusion::VectorFlag::kBeyondSearch}),
                                 dir.path());
  EXPECT_EQ(grid.column("flag").at<double>(0, 0), 0.0);
  EXPECT_EQ(grid.column("flag").at<double>(0, 1), 6.0);
  EXPECT_EQ(grid.column("peak_ratio").at<double>(0, 0), 3.2) << "the columns after flag stay in place";
  std::ofstream(dir / "bad.csv") << "x,y,u,v,valid,flag,peak_ratio\n8,8,1,1,1,beyond,2\n";
  EXPECT_NE(error_of(dir / "bad.csv", kDisplacementColumns).find("line 2: 'beyond' is not a flag"), std::string::npos)
      << error_of(dir / "bad.csv", kDisplacementColumns);
}

TEST(FieldCsv, OnlyTheColumnsAddedLaterMayBeMissing) {
  testing::TempDir dir;
  const auto path = dir / "d.csv";
  std::ofstream(path) << "x,y,u,v,valid,peak_ratio,sigma_u\n8,8,1,1,1,2,0.1\n";
  EXPECT_EQ(read_stored_field(path, kDisplacementColumns).column("sigma_u").at<double>(0, 0), 0.1);
  std::ofstream(path) << "x,y,u,v,valid\n8,8,1,1,1\n";
  EXPECT_NE(error_of(path, kDisplacementColumns).find("the header is 'x,y,u,v,valid'"), std::string::npos);
}

TEST(FieldCsv, EmptyCellsAndMissingNodesAreNaN) {
  testing::TempDir dir;
  std::ofstream(dir / "t.csv") << "x,y,temperature_c,measured,sigma_c\r\n8.0,8.0,30.5,1,0.01\r\n16.0,8.0,,0,nan\r\n"
                               << "8.0,16.0,25.0,1,0.02\r\n";
  const auto grid = read_stored_field(dir / "t.csv", kTemperatureColumns);
  ASSERT_EQ(grid.rows(), 2);
  ASSERT_EQ(grid.cols(), 2);
  EXPECT_TRUE(std::isnan(grid.column("temperature_c").at<double>(0, 1))) << "an empty cell";
  EXPECT_TRUE(std::isnan(grid.column("sigma_c").at<double>(0, 1))) << "a nan cell";
  EXPECT_EQ(grid.column("sigma_c").at<double>(1, 0), 0.02);
  EXPECT_EQ(grid.column("measured").at<double>(0, 1), 0.0);
  EXPECT_TRUE(std::isnan(grid.column("measured").at<double>(1, 1))) << "a node the file does not have";
  EXPECT_EQ(grid.present.at<std::uint8_t>(1, 1), 0);
  EXPECT_EQ(grid.present.at<std::uint8_t>(1, 0), 1);
}

TEST(FieldCsv, MistakesNameTheFileAndLine) {
  testing::TempDir dir;
  const auto path = dir / "bad.csv";
  std::ofstream(path) << "x,y,u,v\n8,8,1,1\n";
  EXPECT_NE(error_of(path, kDisplacementColumns).find("bad.csv': the header is 'x,y,u,v'"), std::string::npos)
      << error_of(path, kDisplacementColumns);
  std::ofstream(path) << "x,y,temperature_c,measured,sigma_c\n8,8,1,1,0\n16,8,1\n";
  EXPECT_NE(error_of(path, kTemperatureColumns).find("line 3: 3 cells, expected 5"), std::string::npos)
      << error_of(path, kTemperatureColumns);
  std::ofstream(path) << "x,y,temperature_c,measured,sigma_c\n8,8,hot,1,0\n";
  EXPECT_NE(error_of(path, kTemperatureColumns).find("line 2: 'hot' is not a number"), std::string::npos)
      << error_of(path, kTemperatureColumns);
  std::ofstream(path) << "x,y,temperature_c,measured,sigma_c\n,8,1,1,0\n";
  EXPECT_NE(error_of(path, kTemperatureColumns).find("line 2: '' is not a number"), std::string::npos)
      << "a node needs a position";
  std::ofstream(path) << "x,y,temperature_c,measured,sigma_c\n8,8,1,1,0\n8,8,2,1,0\n";
  EXPECT_NE(error_of(path, kTemperatureColumns).find("appears twice"), std::string::npos);
  std::ofstream(path) << "x,y,temperature_c,measured,sigma_c\n";
  EXPECT_NE(error_of(path, kTemperatureColumns).find("holds no grid"), std::string::npos);
  EXPECT_NE(error_of(dir / "none.csv", kTemperatureColumns).find("cannot read"), std::string::npos);
}

TEST(DisplacementField, CsvHasTheHeaderAndOneLinePerVector) {
  const fusion::DisplacementField field =
      row_of_two({7.5, 7.5, 0.25, -1.5, 3.2, fusion::VectorFlag::kOk, false, 0.0123, 0.00456},
                 {15.5, 7.5, 0, 0, 0, fusion::VectorFlag::kMasked});
  std::ostringstream out;
  write_csv(field, out);
  EXPECT_EQ(out.str(),
            "x,y,u,v,valid,flag,peak_ratio,sigma_u,sigma_v\n"
            "7.5,7.5,0.25000,-1.50000,1,ok,3.200,0.01230,0.00456\n"
            "15.5,7.5,0.00000,0.00000,0,masked,0.000,0.00000,0.00000\n");
  EXPECT_EQ(field.count_valid(), 1u);
  EXPECT_EQ(field.count(fusion::VectorFlag::kMasked), 1u);
}

TEST(TemperatureField, TheCsvHasANodePerLineItsSigmaAndNanWhereNoValueExists) {
  fusion::TemperatureField field;
  field.rows = 1;
  field.cols = 2;
  field.x0_px = 7.5;
  field.y0_px = 7.5;
  field.step_px = 8;
  field.temperature_c = {25.5, std::nan("")};
  field.measured = {1, 0};
  field.sigma_c = {0.0123456, std::nan("")};
  const auto path = std::filesystem::temp_directory_path() / "bosfuse-temperature-csv-test.csv";
  write_csv(field, path);
  std::ifstream in(path);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::filesystem::remove(path);
  EXPECT_EQ(text, "x,y,temperature_c,measured,sigma_c\n7.5,7.5,25.5000,1,0.01235\n15.5,7.5,nan,0,nan\n");
}

}  // namespace
}  // namespace bosfuse::pipeline
