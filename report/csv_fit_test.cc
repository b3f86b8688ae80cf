#include "report/csv_fit.h"

#include <gtest/gtest.h>

#include <sstream>

namespace bosfuse::report {
namespace {

CsvSeries series_at(std::vector<double> time_s) {
  CsvSeries s;
  s.time_name = "t_s";
  s.temperature_name = "T";
  s.time_s = std::move(time_s);
  s.temperature_c.assign(s.time_s.size(), 30.0);
  return s;
}

TEST(CsvFit, ExperimentSecondsKeepTheFilesOriginAndEpochSecondsDoNot) {
  fitting::NewtonFitOptions options;
  options.origin_s = 42;
  EXPECT_EQ(with_csv_origin(options, series_at({-5, 0, 10})).origin_s, 0.0);
  EXPECT_EQ(with_csv_origin(options, series_at({1.8e9, 1.8e9 + 10})).origin_s, 42);
}

TEST(CsvFit, TheHeaderSaysWhatWasFittedAgainstWhatAndTheTimeScale) {
  CsvSeries s = series_at({0, 1});
  s.iso_origin_ns = 0;
  s.time_scale = 16;
  s.empty_rows = 2;
  std::ostringstream out;
  print_csv_fit_header(out, s, "-", 0);
  EXPECT_EQ(out.str(),
            "standard input: 'T' against 't_s' (t = 0 at 1970-01-01T00:00:00.000000Z; experiment seconds: the "
            "recorded times × 16, the file's time_scale); 2 rows with an empty cell skipped\n");
}

}  // namespace
}  // namespace bosfuse::report
