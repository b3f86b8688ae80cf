#include "acquisition/cameras/genicam_link_budget.h"

#include <fmt/format.h>

namespace bosfuse::acquisition {

std::string GenicamLinkBudget::problem() const {
  if (!(frame_rate_hz > 0) || payload_bytes <= 0 || !(link_bytes_per_s > 0)) return "";
  const double required = required_bytes_per_s();
  if (required <= link_bytes_per_s) return "";
  return fmt::format(
      "{:g} frames/s × {} bytes (PayloadSize) = {:.1f} MB/s is more than the camera's link carries: {} = {:.1f} MB/s "
      "(at most {:.1f} frames/s of this size; a smaller region, a shallower pixel format or a lower rate fits)",
      frame_rate_hz, payload_bytes, required * 1e-6, link_feature, link_bytes_per_s * 1e-6,
      link_bytes_per_s / static_cast<double>(payload_bytes));
}

double genicam_link_bytes_per_s(const std::string& feature, double value) {
  if (feature == "GevLinkSpeed") return value * 1e6 / 8;  // Mbit/s
  if (feature == "DeviceLinkThroughputLimit" || feature == "DeviceLinkSpeed") return value;
  return 0;
}

}  // namespace bosfuse::acquisition
