#include "fitting/uncertainty_digits.h"

#include <gtest/gtest.h>

#include <limits>

namespace bosfuse::fitting {
namespace {

TEST(UncertaintyDigits, TwoSignificantDigitsOfTheUncertainty) {
  EXPECT_EQ(uncertainty_decimals(3.5e-5), 6);
  EXPECT_EQ(uncertainty_decimals(0.232), 2);
  EXPECT_EQ(uncertainty_decimals(3.5), 1);
  EXPECT_EQ(uncertainty_decimals(35.0), 0);
  EXPECT_EQ(uncertainty_decimals(0.0), std::nullopt);
  EXPECT_EQ(uncertainty_decimals(std::numeric_limits<double>::quiet_NaN()), std::nullopt);
}

TEST(UncertaintyDigits, TheValueIsRoundedToTheUncertaintysPlace) {
  EXPECT_EQ(format_at_uncertainty(0.0122926, 3.5e-5), "0.012293");
  EXPECT_EQ(format_at_uncertainty(3.5e-5, 3.5e-5), "0.000035");
  EXPECT_EQ(format_at_uncertainty(78.3999, 0.0569), "78.400");
  EXPECT_EQ(format_at_uncertainty(1234.6, 35.0), "1235");  // σ to two digits: the units place
  EXPECT_EQ(format_at_uncertainty(78.3999, 0.0), "78.3999");  // no σ: six significant digits
}

}  // namespace
}  // namespace bosfuse::fitting
