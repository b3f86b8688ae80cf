#pragma once
// LiveProbes is what the live page (`bosfuse view`, `acquire --live`)
// evaluates of each new frame while a run records: the displacement at every
// thermocouple's image position in probe mode with the run's settings (as
// `process` resolves them; refinement may stop once converged, where
// `process` runs every pass, a difference under 0.001 px), the BOS
// temperature there, the frame's image quality index against the reference
// and a small grey view of the frame — from one decoding of the frame and
// without the full field.
//
// The temperature comes from the run's calibration when it has one
// (probe_calibration.h, as in `process`). Otherwise the physical model of
// the run's geometry gives it without a full field: the displacement is
// evaluated over a band of the image through the probe, the whole width and
// a few windows tall, at a step of one window (an integral needs the
// gradient, not resolution) in two passes, and integrated by
// temperature_field.h's least squares with the band's top and bottom open
// and its left and right ends ambient air — as they are when a plume rises
// in the middle of the image.
// That is a few hundred windows a probe instead of the field's hundreds of
// thousands. Away from the plume's edges it agrees with the full field's
// temperature to about the noise a single band carries.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "fusion/image_quality.h"
#include "storage/records.h"

namespace bosfuse::pipeline {

struct LiveProbeOptions {
  int thumbnail_width_px = 640;  // the frame's view on the page, at most this wide
  int band_windows = 3;          // node rows of the band integrated for the temperature
  // Passes over the band (at most the settings' own): the second, deformed,
  // one moved the demo's band temperatures by 0.5 °C towards the truth, a
  // third by under 0.1 °C more at half again the time.
  int band_passes = 2;

  std::string Validate() const;  // empty when valid
};

struct LiveProbe {
  std::int64_t channel_id = 0;
  std::string name;
  cv::Point2d position_px;
  double u_px = 0, v_px = 0, shift_px = 0;
  bool valid = false;
  std::optional<double> temperature_c;  // none: no source, or the band could not be integrated
};

struct LiveFrame {
  storage::FrameRecord frame;
  std::vector<LiveProbe> probes;
  fusion::QualityIndex quality;  // the frame against the run's reference frame
  cv::Mat thumbnail;             // CV_8U grey, at most thumbnail_width_px wide
  double decode_seconds = 0;
  double evaluate_seconds = 0;  // probes, temperatures, quality index and thumbnail
};

class LiveProbes {
 public:
  // Reads the run's settings (as `process` resolves them), reference frame,
  // positioned channels, calibration and ambient. Throws std::runtime_error
  // saying what is missing — no reference frame yet, or no channel with an
  // image position.
  explicit LiveProbes(const std::filesystem::path& run_dir, LiveProbeOptions options = {});

  LiveFrame evaluate(const storage::FrameRecord& frame) const;

  const std::vector<storage::ChannelInfo>& channels() const { return channels_; }
  std::int64_t reference_frame_id() const { return reference_id_; }
  // "calibration", "physical model (geometry from …)" or "none (…)".
  const std::string& temperature_source() const { return temperature_source_; }
  // Seconds to add to a frame's time to put it on the thermocouples' clock.
  double camera_offset_s() const { return camera_offset_s_; }

  struct Context;  // what every frame's evaluation needs, read once (live_probes.cc)

 private:
  std::shared_ptr<const Context> context_;
  std::vector<storage::ChannelInfo> channels_;
  std::int64_t reference_id_ = 0;
  std::string temperature_source_;
  double camera_offset_s_ = 0;
};

}  // namespace bosfuse::pipeline
