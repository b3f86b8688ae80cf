#include "acquisition/cameras/genicam_source.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "acquisition/cameras/genicam_glib.h"
#include "acquisition/cameras/genicam_link_budget.h"
#include "acquisition/cameras/genicam_pixels.h"
#include "acquisition/clock.h"

namespace bosfuse::acquisition {
using namespace genicam_detail;
namespace {

using GenicamClock = std::chrono::steady_clock;

std::string genicam_number(double value) { return fmt::format("{:g}", value); }

[[noreturn]] void genicam_refuse(const std::string& key, const std::string& message) {
  throw GenicamSettingRefused(key + ": " + message);
}

// The feature's float range; `value` outside it is refused naming both.
void genicam_require_float_in(ArvDevice* device, const char* feature, double value, const std::string& key,
                              const char* unit) {
  double low = 0, high = 0;
  GError* error = nullptr;
  arv_device_get_float_feature_bounds(device, feature, &low, &high, &error);
  genicam_check(error, std::string("reading the range of ") + feature);
  if (value < low || value > high) {
    genicam_refuse(key, fmt::format("{} {} {} is outside the camera's range [{}, {}] {}", feature,
                                    genicam_number(value), unit, genicam_number(low), genicam_number(high), unit));
  }
}

void genicam_require_integer_in(ArvDevice* device, const char* feature, std::int64_t value, const std::string& key) {
  gint64 low = 0, high = 0;
  GError* error = nullptr;
  arv_device_get_integer_feature_bounds(device, feature, &low, &high, &error);
  genicam_check(error, std::string("reading the range of ") + feature);
  if (value < low || value > high) {
    genicam_refuse(key, fmt::format("{} {} is outside the camera's range [{}, {}]", feature, value, low, high));
  }
}

void genicam_require_entry(ArvDevice* device, const char* feature, const std::string& value, const std::string& key) {
  const std::vector<std::string> entries = genicam_enumeration(device, feature);
  if (std::find(entries.begin(), entries.end(), value) != entries.end()) return;
  genicam_refuse(key,
                 fmt::format("{} \"{}\" is not one the camera offers ({})", feature, value, fmt::join(entries, ", ")));
}

void genicam_set_float(ArvDevice* device, const char* feature, double value) {
  GError* error = nullptr;
  arv_device_set_float_feature_value(device, feature, value, &error);
  genicam_check(error, fmt::format("setting {} to {}", feature, genicam_number(value)));
}

// The mono format to stream: the one asked for, which the camera must
// offer, else the deepest it offers.
std::string genicam_choose_format(ArvDevice* device, const std::string& wanted) {
  const std::vector<std::string> offered = genicam_enumeration(device, "PixelFormat");
  if (!wanted.empty()) {
    genicam_require_entry(device, "PixelFormat", wanted, "pixel_format");
    return wanted;
  }
  for (const std::string& format : genicam_mono_formats()) {
    if (std::find(offered.begin(), offered.end(), format) != offered.end()) return format;
  }
  genicam_refuse("pixel_format",
                 fmt::format("the camera offers no mono format bosfuse records ({})", fmt::join(offered, ", ")));
}

void genicam_apply_roi(ArvCamera* camera, const GenicamRoi& roi) {
  gint sensor_w = 0, sensor_h = 0;
  GError* error = nullptr;
  arv_camera_get_sensor_size(camera, &sensor_w, &sensor_h, &error);
  genicam_check(error, "reading the sensor size");
  if (roi.x_px + roi.width_px > sensor_w || roi.y_px + roi.height_px > sensor_h) {
    genicam_refuse("roi_px", fmt::format("[{}, {}, {}, {}] does not fit the sensor's {}×{} pixels (Width, Height, "
                                         "OffsetX, OffsetY)",
                                         roi.x_px, roi.y_px, roi.width_px, roi.height_px, sensor_w, sensor_h));
  }
  ArvDevice* device = arv_camera_get_device(camera);
  genicam_require_integer_in(device, "Width", roi.width_px, "roi_px");
  genicam_require_integer_in(device, "Height", roi.height_px, "roi_px");
  arv_camera_set_region(camera, static_cast<gint>(roi.x_px), static_cast<gint>(roi.y_px),
                        static_cast<gint>(roi.width_px), static_cast<gint>(roi.height_px), &error);
  genicam_check(error, "setting the region of interest");
  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(camera, &x, &y, &w, &h, &error);
  genicam_check(error, "reading the region of interest back");
  if (x != roi.x_px || y != roi.y_px || w != roi.width_px || h != roi.height_px) {
    genicam_refuse("roi_px", fmt::format("[{}, {}, {}, {}] became [{}, {}, {}, {}] on the camera (its Width, Height "
                                         "and offset increments)",
                                         roi.x_px, roi.y_px, roi.width_px, roi.height_px, x, y, w, h));
  }
}

void genicam_apply_exposure_gain(ArvDevice* device, const GenicamOptions& o) {
  if (o.exposure_us) {
    const char* feature = genicam_first_feature(device, {"ExposureTime", "ExposureTimeAbs"});
    if (feature == nullptr) genicam_refuse("exposure_us", "the camera has no ExposureTime feature");
    genicam_require_float_in(device, feature, *o.exposure_us, "exposure_us", "µs");
    genicam_set_float(device, feature, *o.exposure_us);
  }
  if (o.gain_db) {
    if (!genicam_has_feature(device, "Gain")) {
      const bool raw = genicam_has_feature(device, "GainRaw");
      genicam_refuse("gain_db",
                     std::string("the camera has no Gain feature in dB") +
                         (raw ? "; it has GainRaw, in its own units: set it with features = { GainRaw = N }" : ""));
    }
    genicam_require_float_in(device, "Gain", *o.gain_db, "gain_db", "dB");
    genicam_set_float(device, "Gain", *o.gain_db);
  }
}

const char* genicam_rate_feature(ArvDevice* device) {
  return genicam_first_feature(device, {"AcquisitionFrameRate", "AcquisitionFrameRateAbs"});
}

void genicam_apply_frame_rate(ArvCamera* camera, const GenicamOptions& o) {
  if (!o.frame_rate_hz) return;
  ArvDevice* device = arv_camera_get_device(camera);
  const char* feature = genicam_rate_feature(device);
  if (feature == nullptr) genicam_refuse("frame_rate_hz", "the camera has no AcquisitionFrameRate feature");
  genicam_require_float_in(device, feature, *o.frame_rate_hz, "frame_rate_hz", "Hz");
  if (o.exposure_us && *o.exposure_us > 1e6 / *o.frame_rate_hz) {
    genicam_refuse("exposure_us", fmt::format("{} µs is longer than the frame period of frame_rate_hz = {} ({} µs)",
                                              genicam_number(*o.exposure_us), genicam_number(*o.frame_rate_hz),
                                              genicam_number(1e6 / *o.frame_rate_hz)));
  }
  GError* error = nullptr;
  arv_camera_set_frame_rate(camera, *o.frame_rate_hz, &error);  // also sets the enable flag where there is one
  genicam_check(error, "setting the frame rate");
}

// The least throughput the camera reports for its link, into `budget`.
// A feature that cannot be read is no figure to refuse by.
void genicam_read_link(ArvDevice* device, GenicamLinkBudget& budget) {
  bool limit_on = true;  // a camera with a limit and no mode switch enforces it
  if (genicam_has_feature(device, "DeviceLinkThroughputLimitMode")) {
    GError* error = nullptr;
    const char* mode = arv_device_get_string_feature_value(device, "DeviceLinkThroughputLimitMode", &error);
    limit_on = error == nullptr && mode != nullptr && std::string(mode) == "On";
    genicam_take(error);
  }
  for (const std::string feature : {"DeviceLinkThroughputLimit", "DeviceLinkSpeed", "GevLinkSpeed"}) {
    if (!genicam_has_feature(device, feature.c_str()) || (feature == "DeviceLinkThroughputLimit" && !limit_on)) continue;
    GError* error = nullptr;
    const double value = ARV_IS_GC_FLOAT(arv_device_get_feature(device, feature.c_str()))
                             ? arv_device_get_float_feature_value(device, feature.c_str(), &error)
                             : static_cast<double>(arv_device_get_integer_feature_value(device, feature.c_str(), &error));
    if (!genicam_take(error).empty()) continue;
    const double bytes_per_s = genicam_link_bytes_per_s(feature, value);
    if (bytes_per_s > 0 && (budget.link_bytes_per_s == 0 || bytes_per_s < budget.link_bytes_per_s)) {
      budget.link_bytes_per_s = bytes_per_s;
      budget.link_feature = feature;
    }
  }
}

// A requested rate (free-run, or a software trigger's) whose frames the
// camera's link cannot carry is refused at start, naming the figures.
void genicam_check_link(ArvCamera* camera, const GenicamOptions& o) {
  GenicamLinkBudget budget;
  if (o.trigger == GenicamTrigger::kSoftware) {
    budget.frame_rate_hz = 1 / std::chrono::duration<double>(o.software_trigger_period).count();
  } else if (o.trigger == GenicamTrigger::kFreeRun && o.frame_rate_hz) {
    budget.frame_rate_hz = *o.frame_rate_hz;
  }
  if (!(budget.frame_rate_hz > 0)) return;
  genicam_read_link(arv_camera_get_device(camera), budget);
  if (budget.link_bytes_per_s <= 0) return;
  GError* error = nullptr;
  budget.payload_bytes = arv_camera_get_payload(camera, &error);
  genicam_check(error, "reading the payload size");
  if (const std::string problem = budget.problem(); !problem.empty()) {
    genicam_refuse(o.trigger == GenicamTrigger::kSoftware ? "trigger_period_s" : "frame_rate_hz", problem);
  }
}

void genicam_apply_trigger(ArvCamera* camera, const GenicamOptions& o) {
  ArvDevice* device = arv_camera_get_device(camera);
  GError* error = nullptr;
  if (o.trigger == GenicamTrigger::kFreeRun) {
    if (genicam_has_feature(device, "TriggerMode")) arv_camera_clear_triggers(camera, &error);
    genicam_check(error, "switching triggers off");
    return;
  }
  if (!genicam_has_feature(device, "TriggerMode")) genicam_refuse("trigger", "the camera has no TriggerMode feature");
  const std::string source = o.trigger == GenicamTrigger::kSoftware ? "Software" : o.trigger_line;
  genicam_require_entry(device, "TriggerSource", source, o.trigger == GenicamTrigger::kSoftware ? "trigger" : "line");
  arv_camera_set_trigger(camera, source.c_str(), &error);
  genicam_check(error, "setting the trigger to " + source);
  if (o.trigger == GenicamTrigger::kHardware && genicam_has_feature(device, "TriggerActivation")) {
    genicam_require_entry(device, "TriggerActivation", o.trigger_edge, "edge");
    arv_device_set_string_feature_value(device, "TriggerActivation", o.trigger_edge.c_str(), &error);
    genicam_check(error, "setting TriggerActivation to " + o.trigger_edge);
  }
}

void genicam_apply_feature(ArvDevice* device, const GenicamFeature& f) {
  const std::string key = "features." + f.name;
  ArvGcNode* node = arv_device_get_feature(device, f.name.c_str());
  if (node == nullptr || !genicam_has_feature(device, f.name.c_str())) {
    genicam_refuse(key, "the camera has no feature " + f.name);
  }
  GError* error = nullptr;
  const char* name = f.name.c_str();
  if (const auto* text = std::get_if<std::string>(&f.value)) {
    if (ARV_IS_GC_ENUMERATION(node)) genicam_require_entry(device, name, *text, key);
    arv_device_set_string_feature_value(device, name, text->c_str(), &error);
  } else if (const auto* flag = std::get_if<bool>(&f.value)) {
    arv_device_set_boolean_feature_value(device, name, *flag, &error);
  } else if (ARV_IS_GC_INTEGER(node) && std::holds_alternative<std::int64_t>(f.value)) {
    genicam_require_integer_in(device, name, std::get<std::int64_t>(f.value), key);
    arv_device_set_integer_feature_value(device, name, std::get<std::int64_t>(f.value), &error);
  } else if (ARV_IS_GC_FLOAT(node)) {
    const double value = std::holds_alternative<double>(f.value) ? std::get<double>(f.value)
                                                                 : static_cast<double>(std::get<std::int64_t>(f.value));
    genicam_require_float_in(device, name, value, key, "");
    arv_device_set_float_feature_value(device, name, value, &error);
  } else {
    genicam_refuse(key, "the value's type does not suit the camera's feature " + f.name);
  }
  genicam_check(error, "setting " + f.name);
}

std::string genicam_buffer_status(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "missing packets";
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "timed out";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "larger than its buffer";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "wrong packet id";
    case ARV_BUFFER_STATUS_ABORTED:
      return "aborted";
    case ARV_BUFFER_STATUS_CLEARED:
      return "cleared";
    case ARV_BUFFER_STATUS_FILLING:
      return "still filling";
    default:
      return "status " + std::to_string(static_cast<int>(status));
  }
}

void genicam_on_control_lost(ArvDevice*, gpointer flag) { static_cast<std::atomic<bool>*>(flag)->store(true); }

}  // namespace

struct GenicamSource::Handles {
  GObjectPtr<ArvCamera> camera;
  GObjectPtr<ArvStream> stream;
  gulong control_lost_handler = 0;
  const char* latch_command = nullptr;  // GevTimestampControlLatch or TimestampLatch
  const char* latch_value = nullptr;    // GevTimestampValue or TimestampLatchValue
  double latch_ns_per_tick = 1;

  ArvDevice* device() const { return arv_camera_get_device(camera.get()); }
  ~Handles() {
    stream.reset();  // its thread ends before the camera goes
    if (camera && control_lost_handler != 0) g_signal_handler_disconnect(device(), control_lost_handler);
  }
};

GenicamSource::GenicamSource(GenicamOptions options) : options_(std::move(options)) {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("GenICam camera: " + problem);
  }
}

GenicamSource::~GenicamSource() {
  disconnect();
  releases_.clear();  // waits for cameras still being released
}

void GenicamSource::apply_settings() {
  ArvCamera* camera = handles_->camera.get();
  ArvDevice* device = handles_->device();
  GError* error = nullptr;
  if (genicam_has_feature(device, "AcquisitionStop")) arv_camera_stop_acquisition(camera, &error);
  genicam_take(error);  // a camera left streaming by a previous run; not streaming is fine too
  streaming_ = {};
  streaming_.pixel_format = genicam_choose_format(device, options_.pixel_format);
  arv_camera_set_pixel_format_from_string(camera, streaming_.pixel_format.c_str(), &error);
  genicam_check(error, "setting PixelFormat to " + streaming_.pixel_format);
  if (options_.roi) genicam_apply_roi(camera, *options_.roi);
  genicam_apply_exposure_gain(device, options_);
  genicam_apply_frame_rate(camera, options_);
  genicam_apply_trigger(camera, options_);
  for (const GenicamFeature& f : options_.features) genicam_apply_feature(device, f);
  gint x = 0, y = 0;
  arv_camera_get_region(camera, &x, &y, &streaming_.width_px, &streaming_.height_px, &error);
  genicam_check(error, "reading the region of interest");
  if (const char* rate = genicam_rate_feature(device)) {
    streaming_.frame_rate_hz = arv_device_get_float_feature_value(device, rate, &error);
    genicam_check(error, std::string("reading ") + rate);
  }
  // The rate the camera says it will deliver with every setting applied.
  if (options_.frame_rate_hz && streaming_.frame_rate_hz < *options_.frame_rate_hz * (1 - 1e-3)) {
    genicam_refuse("frame_rate_hz",
                   fmt::format("the camera delivers at most {} Hz with these settings, not {} Hz",
                               genicam_number(streaming_.frame_rate_hz), genicam_number(*options_.frame_rate_hz)));
  }
  if (options_.trigger == GenicamTrigger::kSoftware && streaming_.frame_rate_hz > 0 &&
      std::chrono::duration<double>(options_.software_trigger_period).count() < 1 / streaming_.frame_rate_hz) {
    genicam_refuse("trigger_period_s", fmt::format("shorter than the camera's frame period ({} Hz)",
                                                   genicam_number(streaming_.frame_rate_hz)));
  }  genicam_check_link(camera, options_);
}

void GenicamSource::start_stream() {
  ArvCamera* camera = handles_->camera.get();
  GError* error = nullptr;
  const guint payload = arv_camera_get_payload(camera, &error);
  genicam_check(error, "reading the payload size");
  handles_->stream.reset(arv_camera_create_stream(camera, nullptr, nullptr, &error));
  genicam_check(error, "creating the stream");
  if (!handles_->stream) throw DeviceError(describe() + ": no stream");
  if (ARV_IS_GV_STREAM(handles_->stream.get()) && !options_.packet_resend) {
    g_object_set(handles_->stream.get(), "packet-resend", ARV_GV_STREAM_PACKET_RESEND_NEVER, nullptr);
  }
  for (int i = 0; i < options_.buffer_count; ++i) {
    arv_stream_push_buffer(handles_->stream.get(), arv_buffer_new(payload, nullptr));
  }
  arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  genicam_check(error, "setting continuous acquisition");
  arv_camera_start_acquisition(camera, &error);
  genicam_check(error, "starting acquisition");
}

void GenicamSource::connect() {
  disconnect();
  auto handles = std::make_unique<Handles>();
  handles->camera = genicam_open(options_.device);
  control_lost_ = false;
  gone_ = false;
  handles->control_lost_handler =
      g_signal_connect(handles->device(), "control-lost", G_CALLBACK(genicam_on_control_lost), &control_lost_);
  ArvDevice* device = handles->device();
  handles->latch_command = genicam_first_feature(device, {"GevTimestampControlLatch", "TimestampLatch"});
  handles->latch_value = genicam_first_feature(device, {"GevTimestampValue", "TimestampLatchValue"});
  if (handles->latch_command != nullptr && handles->latch_value != nullptr &&
      std::string(handles->latch_command) == "GevTimestampControlLatch" &&
      genicam_has_feature(device, "GevTimestampTickFrequency")) {
    GError* error = nullptr;
    const gint64 hz = arv_device_get_integer_feature_value(device, "GevTimestampTickFrequency", &error);
    genicam_take(error);
    handles->latch_ns_per_tick = hz > 0 ? 1e9 / static_cast<double>(hz) : 0;
  }
  handles_ = std::move(handles);
  try {
    apply_settings();
    streaming_.latched_clock =
        handles_->latch_command != nullptr && handles_->latch_value != nullptr && handles_->latch_ns_per_tick > 0;
    start_stream();
  } catch (...) {
    disconnect();
    throw;
  }
  // A reconnected camera may have restarted its clock: a new mapping, fitted
  // as its pairs' errors require (genicam_clock_mapping.h).
  clock_ = GenicamClockMapping(streaming_.latched_clock ? GenicamClockMapping::Pairs::kLatched
                                                        : GenicamClockMapping::Pairs::kArrivals);
  clock_noted_ = false;
  last_frame_id_.reset();
  last_frame_at_ = next_trigger_at_ = next_latch_at_ = GenicamClock::now();
  next_clock_note_at_ = last_frame_at_ + options_.clock_report_period;
  rate_since_ = last_frame_at_;
  rate_frames_ = frames_read_;
  resent_packets_ = missing_packets_ = 0;  // a new stream counts from 0
}

void GenicamSource::disconnect() {
  if (!handles_) return;
  if (handles_->control_lost_handler != 0) {
    g_signal_handler_disconnect(handles_->device(), handles_->control_lost_handler);
    handles_->control_lost_handler = 0;
  }
  if (!control_lost_ && !gone_) {
    GError* error = nullptr;
    arv_camera_stop_acquisition(handles_->camera.get(), &error);
    genicam_take(error);
    handles_.reset();
    return;
  }
  std::erase_if(releases_, [](const std::future<void>& f) {
    return f.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  });
  releases_.push_back(std::async(std::launch::async,
                                 [gone = std::shared_ptr<Handles>(std::move(handles_))]() mutable { gone.reset(); }));
}

GenicamSource::Streaming GenicamSource::check_settings(const GenicamOptions& options) {
  GenicamSource source(options);
  source.handles_ = std::make_unique<Handles>();
  source.handles_->camera = genicam_open(options.device);
  source.apply_settings();  // no stream: the settings alone
  return source.streaming();
}

void GenicamSource::software_trigger_if_due() {
  if (options_.trigger != GenicamTrigger::kSoftware) return;
  const auto now = GenicamClock::now();
  if (now < next_trigger_at_) return;
  GError* error = nullptr;
  arv_camera_software_trigger(handles_->camera.get(), &error);
  genicam_check(error, describe() + ": software trigger");
  next_trigger_at_ += std::chrono::duration_cast<GenicamClock::duration>(options_.software_trigger_period);
  if (next_trigger_at_ < now) next_trigger_at_ = now + options_.software_trigger_period;  // fell behind: no burst
}

void GenicamSource::latch_clock_if_due() {
  if (!streaming_.latched_clock || GenicamClock::now() < next_latch_at_) return;
  next_latch_at_ += options_.latch_period;
  ArvDevice* device = handles_->device();
  GError* error = nullptr;
  const std::int64_t before_ns = utc_now_ns();
  arv_device_execute_command(device, handles_->latch_command, &error);
  const std::int64_t after_ns = utc_now_ns();
  genicam_check(error, describe() + ": latching the timestamp");
  const gint64 ticks = arv_device_get_integer_feature_value(device, handles_->latch_value, &error);
  genicam_check(error, describe() + ": reading the latched timestamp");
  // The latch happened between the two host readings: their middle is the
  // best estimate, and half their spread bounds its error.
  clock_.add(static_cast<std::int64_t>(std::llround(static_cast<double>(ticks) * handles_->latch_ns_per_tick)),
             before_ns + (after_ns - before_ns) / 2);
}

void GenicamSource::probe_if_silent() {
  const auto now = GenicamClock::now();
  auto limit = std::chrono::duration_cast<GenicamClock::duration>(options_.frame_timeout);
  if (options_.trigger == GenicamTrigger::kSoftware) {
    limit += std::chrono::duration_cast<GenicamClock::duration>(options_.software_trigger_period);
  } else if (streaming_.frame_rate_hz > 0) {
    limit +=
        std::chrono::duration_cast<GenicamClock::duration>(std::chrono::duration<double>(1 / streaming_.frame_rate_hz));
  }
  if (now - last_frame_at_ < limit) return;
  guint32 value = 0;
  GError* error = nullptr;
  arv_device_read_register(handles_->device(), 0, &value, &error);
  if (error != nullptr) {
    gone_ = true;
    throw DeviceError(fmt::format("{}: no frame for {:.1f} s and no answer: {}", describe(),
                                  std::chrono::duration<double>(now - last_frame_at_).count(), genicam_take(error)));
  }
  if (options_.trigger != GenicamTrigger::kHardware) {
    notes_.push_back({"error", fmt::format("{}: no frame for {:.1f} s although the camera answers", describe(),
                                           std::chrono::duration<double>(now - last_frame_at_).count())});
  }
  last_frame_at_ = now;  // probed: the next probe after another timeout
}

void GenicamSource::note_frame_gap(std::uint64_t frame_id) {
  if (last_frame_id_) {
    std::uint64_t gap = frame_id - *last_frame_id_;
    // GigE Vision's 16-bit block ids run 1..65535 and skip 0.
    if (frame_id < *last_frame_id_ && *last_frame_id_ <= 0xFFFF) gap = frame_id + 0xFFFF - *last_frame_id_;
    if (gap > 1 && gap < 0x8000) {
      notes_.push_back({"lost-frames",
                        fmt::format("{}: {} frames never arrived (frame ids after {} up to {})", describe(), gap - 1,
                                    *last_frame_id_, frame_id),
                        static_cast<std::int64_t>(gap - 1)});
    }
  }
  last_frame_id_ = frame_id;
}

void GenicamSource::note_stream_statistics() {
  if (!ARV_IS_GV_STREAM(handles_->stream.get())) return;
  guint64 resent = 0, missing = 0;
  arv_gv_stream_get_statistics(ARV_GV_STREAM(handles_->stream.get()), &resent, &missing);
  if (resent == resent_packets_ && missing == missing_packets_) return;
  notes_.push_back(
      {"lost-packets", fmt::format("{}: {} packets resent, {} missing since the last count ({} and {} "
                                   "since the stream started)",
                                   describe(), resent - resent_packets_, missing - missing_packets_, resent, missing)});
  resent_packets_ = resent;
  missing_packets_ = missing;
}

// A camera that sends fewer frames than asked (its frame ids show no gap,
// so none were lost on the way) says so once per report period.
void GenicamSource::note_rate(GenicamClock::time_point now) {
  const double span_s = std::chrono::duration<double>(now - rate_since_).count();
  const double rate_hz = static_cast<double>(frames_read_ - rate_frames_) / span_s;
  rate_since_ = now;
  rate_frames_ = frames_read_;
  if (!options_.frame_rate_hz || options_.trigger != GenicamTrigger::kFreeRun) return;
  if (rate_hz >= 0.9 * *options_.frame_rate_hz) return;
  notes_.push_back({"error", fmt::format("{}: {:.1f} frames/s over the last {:.1f} s, not the {} asked", describe(),
                                         rate_hz, span_s, genicam_number(*options_.frame_rate_hz))});
}

void GenicamSource::note_clock_if_due(bool force) {
  const auto now = GenicamClock::now();
  const bool first = !clock_noted_ && clock_.size() >= 2;
  if (!force && !first && now < next_clock_note_at_) return;
  if (now >= next_clock_note_at_) {
    next_clock_note_at_ = now + options_.clock_report_period;
    note_rate(now);
  }
  note_stream_statistics();
  const std::optional<GenicamClockMapping::Fit> fit = clock_.fit();
  if (!fit || fit->pairs < 2) return;
  clock_noted_ = true;
  notes_.push_back({"clock", describe() + ": camera clock to host, " +
                                 (streaming_.latched_clock ? "from latched timestamps: " : "from frame arrivals: ") +
                                 GenicamClockMapping::describe(*fit)});
}

std::vector<FrameSource::Note> GenicamSource::take_notes() { return std::exchange(notes_, {}); }

namespace {

// A popped buffer goes back to the stream however its frame ends.
class GenicamBufferLease {
 public:
  GenicamBufferLease(ArvStream* stream, ArvBuffer* buffer) : stream_(stream), buffer_(buffer) {}
  ~GenicamBufferLease() { arv_stream_push_buffer(stream_, buffer_); }
  GenicamBufferLease(const GenicamBufferLease&) = delete;
  GenicamBufferLease& operator=(const GenicamBufferLease&) = delete;
  ArvBuffer* get() const { return buffer_; }

 private:
  ArvStream* stream_;
  ArvBuffer* buffer_;
};

}  // namespace

std::optional<CapturedFrame> GenicamSource::take_buffer(std::chrono::milliseconds wait) {
  auto timeout = std::chrono::duration_cast<std::chrono::microseconds>(wait);
  if (options_.trigger == GenicamTrigger::kSoftware) {
    timeout = std::clamp(std::chrono::duration_cast<std::chrono::microseconds>(next_trigger_at_ - GenicamClock::now()),
                         std::chrono::microseconds(1000), timeout);
  }
  ArvBuffer* popped = arv_stream_timeout_pop_buffer(handles_->stream.get(), static_cast<guint64>(timeout.count()));
  if (popped == nullptr) return std::nullopt;
  const std::int64_t popped_ns = utc_now_ns();
  GenicamBufferLease buffer(handles_->stream.get(), popped);
  last_frame_at_ = GenicamClock::now();
  const std::uint64_t frame_id = arv_buffer_get_frame_id(popped);
  note_frame_gap(frame_id);
  if (const ArvBufferStatus status = arv_buffer_get_status(popped); status != ARV_BUFFER_STATUS_SUCCESS) {
    throw FrameLost(fmt::format("{}: frame id {} lost: {}", describe(), frame_id, genicam_buffer_status(status)));
  }
  size_t size = 0;
  const auto* data = static_cast<const std::uint8_t*>(arv_buffer_get_data(popped, &size));
  CapturedFrame frame;
  try {
    frame.image = genicam_pixels_to_image(streaming_.pixel_format, data, size, arv_buffer_get_image_width(popped),
                                          arv_buffer_get_image_height(popped));
  } catch (const std::invalid_argument& e) {
    throw FrameLost(fmt::format("{}: frame id {} lost: {}", describe(), frame_id, e.what()));
  }
  const guint64 arrival = arv_buffer_get_system_timestamp(popped);
  frame.arrival_ns = arrival > 0 ? static_cast<std::int64_t>(arrival) : popped_ns;
  frame.t_ns = *frame.arrival_ns;
  if (const guint64 camera_ns = arv_buffer_get_timestamp(popped); camera_ns > 0) {
    frame.device_t_ns = static_cast<std::int64_t>(camera_ns);
    if (!streaming_.latched_clock) clock_.add(*frame.device_t_ns, *frame.arrival_ns);
    if (const std::optional<std::int64_t> mapped = clock_.map(*frame.device_t_ns)) frame.t_ns = *mapped;
  }
  frame.origin = fmt::format("{} frame id {}", describe(), frame_id);
  ++frames_read_;
  return frame;
}

std::optional<CapturedFrame> GenicamSource::next(std::chrono::milliseconds wait) {
  if (!handles_) throw DeviceError(describe() + " is not open");
  if (control_lost_) {
    gone_ = true;
    throw DeviceError(describe() +
                      ": control lost (the camera stopped answering: unplugged, rebooted, or taken "
                      "by another host)");
  }
  software_trigger_if_due();
  latch_clock_if_due();
  std::optional<CapturedFrame> frame = take_buffer(wait);
  if (!frame) probe_if_silent();
  note_clock_if_due(false);
  return frame;
}

}  // namespace bosfuse::acquisition
