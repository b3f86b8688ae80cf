#include "acquisition/cameras/genicam_options.h"

#include <algorithm>
#include <cmath>

namespace bosfuse::acquisition {
namespace {

struct GenicamFormatBits {
  const char* name;
  int bits;
};

constexpr GenicamFormatBits kGenicamFormats[] = {
    {"Mono16", 16}, {"Mono12", 12},  {"Mono12p", 12},      {"Mono12Packed", 12},
    {"Mono10", 10}, {"Mono10p", 10}, {"Mono10Packed", 10}, {"Mono8", 8},
};

bool genicam_positive(const std::optional<double>& value) { return !value || (std::isfinite(*value) && *value > 0); }

}  // namespace

const std::vector<std::string>& genicam_mono_formats() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const GenicamFormatBits& f : kGenicamFormats) out.emplace_back(f.name);
    return out;
  }();
  return names;
}

int genicam_format_bits(const std::string& pixel_format) {
  for (const GenicamFormatBits& f : kGenicamFormats) {
    if (pixel_format == f.name) return f.bits;
  }
  return 0;
}

std::string GenicamOptions::Validate() const {
  if (device.empty()) return "device must name the camera (Aravis id, serial number or IP address)";
  if (!pixel_format.empty() && genicam_format_bits(pixel_format) == 0) {
    return "pixel_format \"" + pixel_format +
           "\" is not recorded (Mono8, Mono10, Mono10p, Mono10Packed, Mono12, Mono12p, Mono12Packed or Mono16)";
  }
  if (!genicam_positive(exposure_us)) return "exposure_us must be a positive number";
  if (gain_db && !std::isfinite(*gain_db)) return "gain_db must be a finite number";
  if (!genicam_positive(frame_rate_hz)) return "frame_rate_hz must be a positive number";
  if (roi && (roi->x_px < 0 || roi->y_px < 0 || roi->width_px < 1 || roi->height_px < 1)) {
    return "roi_px must be [x, y, width, height] with x, y >= 0 and width, height >= 1";
  }
  if (trigger == GenicamTrigger::kSoftware && software_trigger_period <= std::chrono::nanoseconds::zero()) {
    return "a software trigger needs a positive period";
  }
  if (trigger == GenicamTrigger::kHardware && (trigger_line.empty() || trigger_edge.empty())) {
    return "a hardware trigger needs a line and an edge";
  }
  if (buffer_count < 2 || buffer_count > 1024) return "buffer_count must be between 2 and 1024";
  if (frame_timeout < std::chrono::milliseconds(100)) return "frame_timeout must be at least 100 ms";
  if (latch_period < std::chrono::milliseconds(10)) return "latch_period must be at least 10 ms";
  if (clock_report_period < std::chrono::milliseconds(100)) return "clock_report_period must be at least 100 ms";
  for (const GenicamFeature& f : features) {
    if (f.name.empty()) return "a feature needs a name";
  }
  return {};
}

}  // namespace bosfuse::acquisition
