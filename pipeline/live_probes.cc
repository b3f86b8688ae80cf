#include "pipeline/live_probes.h"


#include <chrono>
#include <cmath>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "fusion/image_input.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/process_frame.h"
#include "pipeline/processing_settings.h"
#include "pipeline/run_selection.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {

namespace fs = std::filesystem;

struct LiveProbes::Context {
  LiveProbeOptions options;
  FrameContext frame;  // the chain of `process`, without a folder for fields
  fusion::GreyMoments reference_moments;
  std::mutex evaluating;
};

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
  return {};
}

// As process_run's frame_context, but nothing is staged: the probes' ids are
// the channels' own.
LiveProbes::LiveProbes(const fs::path& run_dir, LiveProbeOptions options) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  auto ctx = std::make_shared<Context>();
  ctx->options = options;
  const auto store = storage::RunStore::open(run_dir);
  channels_ = positioned_channels(store.channels());
  if (channels_.empty()) throw std::runtime_error("no channel of the run has an image position (position_px)");
  const auto frames = store.frames();
  const auto reference = std::find_if(frames.begin(), frames.end(), [](const auto& f) { return f.is_reference; });
  if (reference == frames.end()) throw std::runtime_error("waiting for the run's reference frame");
  reference_id_ = reference->id;
  FrameContext& frame = ctx->frame;
  frame.run_dir = run_dir;
  frame.reference_frame = *reference;
  frame.settings = resolve_settings(run_dir, {});
  frame.channels = channels_;
  for (const auto& c : channels_) {
    frame.points.emplace_back(*c.image_x_px, *c.image_y_px);
    frame.probe_ids.push_back(c.id);
  }
  resolve_ambient(frame.settings.geometry, store, channels_, storage::experiment_clock(store), *reference);
  frame.calibration = stored_calibration(storage::ProcessingStore(run_dir));
  load_frame_context(frame);
  ctx->reference_moments = fusion::grey_moments(frame.reference, "reference frame");
  log_warnings(ctx->reference_moments.warnings);
  camera_offset_s_ = frame.settings.geometry.camera_offset_s;
  temperature_source_ = pipeline::temperature_source(frame);
  context_ = std::move(ctx);
}

LiveFrame LiveProbes::evaluate(const storage::FrameRecord& frame) const {
  Context& ctx = *context_;
  const std::lock_guard serialised(ctx.evaluating);
  LiveFrame out;
  out.frame = frame;
  auto start = std::chrono::steady_clock::now();
  const cv::Mat measurement = load_frame(ctx.frame.run_dir, frame);
  out.decode_seconds = seconds_since(start);
  start = std::chrono::steady_clock::now();
  const auto samples = probe_samples(ctx.frame, frame, ctx.frame.evaluate(measurement));
  for (std::size_t p = 0; p < channels_.size(); ++p) {
    const auto& s = samples[p];
    out.probes.push_back({channels_[p].id, channels_[p].name, ctx.frame.points[p], s.u_px, s.v_px, s.shift_px, s.valid,
                          s.temperature_c, s.sigma_shift_px, s.sigma_random_c, s.sigma_systematic_c});
  }
  const fusion::GreyMoments moments = fusion::grey_moments(measurement, "frame");
  log_warnings(moments.warnings);
  out.quality = fusion::modified_quality_index(moments, ctx.reference_moments);
  out.thumbnail = thumbnail(measurement, ctx.options.thumbnail_width_px);
  out.evaluate_seconds = seconds_since(start);
  return out;
}

}  // namespace bosfuse::pipeline
