#include "fitting/uncertainty_digits.h"

#include <cmath>
#include <cstdio>

namespace bosfuse::fitting {

namespace {
constexpr int kMostDecimals = 12;  // beyond this fixed notation is a row of zeros
}

std::optional<int> uncertainty_decimals(double std_error) {
  if (!(std_error > 0) || !std::isfinite(std_error)) return std::nullopt;
  const int leading = static_cast<int>(std::floor(std::log10(std_error)));
  const int decimals = leading < 1 ? 1 - leading : 0;
  if (decimals > kMostDecimals) return std::nullopt;
  return decimals;
}

std::string format_at_uncertainty(double value, double std_error) {
  char text[64];
  if (const auto decimals = uncertainty_decimals(std_error); decimals && std::isfinite(value)) {
    std::snprintf(text, sizeof text, "%.*f", *decimals, value);
  } else {
    std::snprintf(text, sizeof text, "%.6g", value);
  }
  return text;
}

}  // namespace bosfuse::fitting
