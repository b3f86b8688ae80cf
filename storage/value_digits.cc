#include "storage/value_digits.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace bosfuse::storage {

std::optional<int> resolution_decimals(std::optional<double> resolution) {
  if (!resolution || !(*resolution > 0) || !std::isfinite(*resolution)) return std::nullopt;
  // The decimal place of the step's leading digit; the small allowance keeps
  // 0.1 (stored as 0.1000000000000000055…) at one decimal, not two.
  const double place = std::ceil(-std::log10(*resolution) - 1e-9);
  return static_cast<int>(std::clamp(place, 0.0, 15.0));
}

std::string format_channel_value(double value, std::optional<double> resolution) {
  if (!std::isfinite(value)) return "";
  const std::optional<int> decimals = resolution_decimals(resolution);
  if (!decimals) return fmt::format("{:.6g}", value);
  std::string text = fmt::format("{:.{}f}", value, *decimals);
  // −0.0 reads as a sign the reading never had.
  if (text.find_first_not_of("-0.") == std::string::npos && text.front() == '-') text.erase(0, 1);
  return text;
}

}  // namespace bosfuse::storage
