// Cleaning a series: rejection counts, sorting, origin, duplicates,
// interpolation.

#include "fitting/series.h"

#include <gtest/gtest.h>

#include <limits>

namespace bosfuse::fitting {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(CleanSeries, DropsNonFiniteSortsAndMovesToTheEarliestTime) {
  const std::vector<double> t{1.8e9 + 3, kNaN, 1.8e9 + 1, 1.8e9 + 2, -kInf, 1.8e9 + 5};
  const std::vector<double> y{30, 1, 10, 20, 2, kInf};
  const auto s = clean_series(t, y);
  EXPECT_EQ(s.rejected_non_finite, 3u);
  EXPECT_EQ(s.origin_s, 1.8e9 + 1);
  EXPECT_EQ(s.time_s, (std::vector<double>{0, 1, 2}));
  EXPECT_EQ(s.temperature_c, (std::vector<double>{10, 20, 30}));
  EXPECT_EQ(s.duration_s(), 2.0);
}

TEST(CleanSeries, KeepsAndCountsDuplicateTimesInInputOrder) {
  const std::vector<double> t{2, 1, 2, 2, 0};
  const std::vector<double> y{21, 10, 22, 23, 0};
  const auto s = clean_series(t, y, 0.0);
  EXPECT_EQ(s.duplicate_times, 2u);
  EXPECT_EQ(s.temperature_c, (std::vector<double>{0, 10, 21, 22, 23})) << "stable: duplicates keep input order";
}

TEST(CleanSeries, AChosenOriginIsUsedAsGiven) {
  const std::vector<double> t{10, 11}, y{1, 2};
  EXPECT_EQ(clean_series(t, y, 4.0).time_s, (std::vector<double>{6, 7}));
  EXPECT_THROW(clean_series(t, y, kNaN), std::invalid_argument);
  EXPECT_THROW(clean_series(t, std::vector<double>{1}), std::invalid_argument);
}

TEST(CleanSeries, InterpolatesLinearlyInsideAndRefusesOutside) {
  const std::vector<double> t{0, 2, 4}, y{10, 20, 0};
  const auto s = clean_series(t, y);
  EXPECT_DOUBLE_EQ(*interpolate(s, 1.0), 15.0);
  EXPECT_DOUBLE_EQ(*interpolate(s, 3.0), 10.0);
  EXPECT_DOUBLE_EQ(*interpolate(s, 0.0), 10.0);
  EXPECT_DOUBLE_EQ(*interpolate(s, 4.0), 0.0);
  EXPECT_FALSE(interpolate(s, -0.1));
  EXPECT_FALSE(interpolate(s, 4.1));
  EXPECT_FALSE(interpolate(CleanSeries{}, 0.0));
}

}  // namespace
}  // namespace bosfuse::fitting
