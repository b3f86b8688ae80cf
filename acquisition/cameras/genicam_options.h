#pragma once
// GenicamOptions are what a GenICam camera (GigE Vision or USB3 Vision,
// through Aravis) is set up with: which camera, its pixel format, exposure,
// gain, frame rate, region of interest, trigger and any other GenICam
// feature by name. Validate() checks what can be checked without the
// camera; the camera's own feature limits are checked when it is opened
// (genicam_source.h), and a setting outside them is refused naming the
// feature and its range.

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace bosfuse::acquisition {

struct GenicamRoi {
  std::int64_t x_px = 0;
  std::int64_t y_px = 0;
  std::int64_t width_px = 0;
  std::int64_t height_px = 0;
};

enum class GenicamTrigger { kFreeRun, kSoftware, kHardware };

// One `features = { Name = value }` entry, set after the named settings.
struct GenicamFeature {
  std::string name;
  std::variant<std::int64_t, double, bool, std::string> value;
};

struct GenicamOptions {
  std::string device;  // Aravis id ("Aravis-Fake-BOS01"), serial number or IP address
  // Empty: the deepest mono format the camera offers, so frames keep the
  // sensor's depth unless the user asks for less.
  std::string pixel_format;
  std::optional<double> exposure_us;
  std::optional<double> gain_db;  // SFNC `Gain`; a camera with only GainRaw refuses it
  std::optional<double> frame_rate_hz;
  std::optional<GenicamRoi> roi;
  GenicamTrigger trigger = GenicamTrigger::kFreeRun;
  std::chrono::nanoseconds software_trigger_period{0};  // kSoftware: one trigger per period
  std::string trigger_line = "Line1";                   // kHardware: TriggerSource
  std::string trigger_edge = "RisingEdge";              // kHardware: TriggerActivation
  std::vector<GenicamFeature> features;
  // GigE Vision: ask the camera to resend lost packets (Aravis' default).
  bool packet_resend = true;
  int buffer_count = 16;  // frames Aravis may hold before the recorder takes them
  // No frame for this long (beyond the frame period) and the camera is
  // probed; one that does not answer is a disconnect.
  std::chrono::milliseconds frame_timeout{2000};
  // How often a camera with a timestamp latch is latched against the host
  // clock for the time mapping (genicam_clock_mapping.h).
  std::chrono::milliseconds latch_period{1000};
  // How often the mapping is written to the run as a "clock" event.
  std::chrono::milliseconds clock_report_period{10'000};

  std::string Validate() const;
};

// The pixel formats bosfuse records, deepest first: Mono16, Mono12,
// Mono12p, Mono12Packed, Mono10, Mono10p, Mono10Packed, Mono8.
const std::vector<std::string>& genicam_mono_formats();
// Significant bits of one of those formats; 0 for any other name.
int genicam_format_bits(const std::string& pixel_format);

}  // namespace bosfuse::acquisition
