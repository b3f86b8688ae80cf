#include "pipeline/live_probes.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/image_input.h"
#include "fusion/temperature_field.h"
#include "pipeline/probe_calibration.h"
#include "pipeline/processing_settings.h"
#include "pipeline/run_selection.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {

namespace fs = std::filesystem;

struct LiveProbes::Context {
  fs::path run_dir;
  LiveProbeOptions options;
  ProcessingSettings settings;
  cv::Mat reference;
  fusion::GreyMoments reference_moments;
  cv::Mat mask;
  std::vector<cv::Point2d> points;
  std::optional<fusion::BosGeometry> geometry;  // none: the calibration gives every temperature
  std::map<std::int64_t, ChannelCalibration> calibration;
};

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The physical model's temperature at `p` from a band of the image through
// it (the header says why a band).
std::optional<double> band_temperature_c(const LiveProbes::Context& ctx, const cv::Mat& measurement, cv::Point2d p) {
  fusion::EvaluatorOptions options = ctx.settings.evaluator;
  const int window = options.xcorr.window_px;
  options.set_grid(window, window);
  options.xcorr.passes = std::min(options.xcorr.passes, ctx.options.band_passes);
  const cv::Size size = ctx.reference.size();
  const int roi_height = (ctx.options.band_windows - 1) * window + window;
  if (size.height < roi_height || size.width < 3 * window) return std::nullopt;
  const int roi_y = std::clamp(static_cast<int>(std::lround(p.y)) - roi_height / 2, 0, size.height - roi_height);
  // The windows' search and interpolation reach beyond the band; crop that
  // much more so the band's windows see what they would in the whole frame.
  const int reach = options.xcorr.search_radius_px(0) + 4;
  const int crop_y = std::max(roi_y - reach, 0);
  const cv::Rect crop(0, crop_y, size.width, std::min(roi_y + roi_height + reach, size.height) - crop_y);
  options.set_grid(window, window, cv::Rect(0, roi_y - crop_y, size.width, roi_height));
  const cv::Mat mask = ctx.mask.empty() ? cv::Mat() : ctx.mask(crop).clone();
  const auto band = fusion::evaluate_displacement(ctx.reference(crop).clone(), measurement(crop).clone(), options, mask);
  if (band.field.rows < 3 || band.field.cols < 3) return std::nullopt;
  fusion::TemperatureFieldOptions field_options = ctx.settings.geometry.temperature_field;
  field_options.open_top = field_options.open_bottom = true;
  field_options.open_left = field_options.open_right = false;
  const auto temperature = fusion::recover_temperature_field(band.field, *ctx.geometry, field_options);
  return temperature.field.temperature_at(p.x, p.y - crop_y);
}

// By a whole factor: OpenCV's area average is then a plain block mean,
// several times faster on a 16 MP frame than an arbitrary scale.
cv::Mat thumbnail(const cv::Mat& image, int max_width_px) {
  cv::Mat grey = image;
  if (grey.channels() == 3) cv::cvtColor(grey, grey, cv::COLOR_BGR2GRAY);
  if (grey.channels() == 4) cv::cvtColor(grey, grey, cv::COLOR_BGRA2GRAY);
  const int factor = (grey.cols + max_width_px - 1) / max_width_px;
  cv::Mat small;
  if (factor > 1) {
    cv::resize(grey, small, cv::Size(grey.cols / factor, grey.rows / factor), 0, 0, cv::INTER_AREA);
  } else {
    small = grey.clone();
  }
  if (small.depth() != CV_8U) small.convertTo(small, CV_8U, 255.0 / fusion::full_scale(small.depth()));
  return small;
}

}  // namespace

std::string LiveProbeOptions::Validate() const {
  if (thumbnail_width_px < 16 || thumbnail_width_px > 4096) return "thumbnail width must be 16 to 4096 px";
  if (band_windows < 3 || band_windows > 15) return "the band must be 3 to 15 windows tall";
  if (band_passes < 1 || band_passes > 5) return "the band needs 1 to 5 passes";
  return {};
}

LiveProbes::LiveProbes(const fs::path& run_dir, LiveProbeOptions options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  auto ctx = std::make_shared<Context>();
  ctx->run_dir = run_dir;
  ctx->options = options;
  const auto store = storage::RunStore::open(run_dir);
  channels_ = positioned_channels(store.channels());
  if (channels_.empty()) throw std::runtime_error("no channel of the run has an image position (position_px)");
  const auto frames = store.frames();
  const auto reference = std::find_if(frames.begin(), frames.end(), [](const auto& f) { return f.is_reference; });
  if (reference == frames.end()) throw std::runtime_error("waiting for the run's reference frame");
  reference_id_ = reference->id;
  ctx->settings = resolve_settings(run_dir, {});
  ctx->reference = load_frame(run_dir, *reference);
  ctx->reference_moments = fusion::grey_moments(ctx->reference, "reference frame");
  ctx->mask = load_mask(run_dir, ctx->settings.mask);
  for (const auto& c : channels_) ctx->points.emplace_back(*c.image_x_px, *c.image_y_px);
  ctx->calibration = stored_calibration(storage::ProcessingStore(run_dir));
  auto& geometry = ctx->settings.geometry;
  camera_offset_s_ = geometry.camera_offset_s;
  if (!ctx->calibration.empty()) {
    temperature_source_ = "calibration";
  } else {
    resolve_ambient(geometry, store, channels_, storage::experiment_clock(store), *reference);
    ctx->geometry.emplace(geometry.geometry);
    temperature_source_ = fmt::format("physical model (geometry from {}, ambient {:.1f} °C)", geometry.source,
                                      geometry.geometry.ambient_temperature_c);
  }
  context_ = std::move(ctx);
}

LiveFrame LiveProbes::evaluate(const storage::FrameRecord& frame) const {
  const Context& ctx = *context_;
  LiveFrame out;
  out.frame = frame;
  auto start = std::chrono::steady_clock::now();
  const cv::Mat measurement = load_frame(ctx.run_dir, frame);
  out.decode_seconds = seconds_since(start);
  start = std::chrono::steady_clock::now();
  const auto evaluated =
      fusion::probe_displacement(ctx.reference, measurement, ctx.points, ctx.settings.evaluator, ctx.mask);
  for (std::size_t p = 0; p < channels_.size(); ++p) {
    const auto& v = evaluated.field.vectors[p];
    LiveProbe probe{channels_[p].id, channels_[p].name, ctx.points[p], v.u_px, v.v_px, std::hypot(v.u_px, v.v_px),
                    v.valid(), std::nullopt};
    if (probe.valid) {
      probe.temperature_c = ctx.geometry ? band_temperature_c(ctx, measurement, ctx.points[p])
                                         : calibrated_temperature_c(ctx.calibration, probe.channel_id, probe.shift_px);
    }
    out.probes.push_back(std::move(probe));
  }
  out.quality = fusion::modified_quality_index(fusion::grey_moments(measurement, "frame"), ctx.reference_moments);
  out.thumbnail = thumbnail(measurement, ctx.options.thumbnail_width_px);
  out.evaluate_seconds = seconds_since(start);
  return out;
}

}  // namespace bosfuse::pipeline
