#pragma once
// LiveProbes is what the live page (`bosfuse view`, `acquire --live`)
// evaluates of each new frame while a run records: the displacement and the
// BOS temperature at every thermocouple's image position, the frame's image
// quality index against the reference and a small grey view of the frame,
// from one decoding of the frame.
//
// Each probe's shift and temperature come from the chain `process` runs
// (process_frame.h): the same settings, reference, mask, ambient,
// calibration and conversion — the full field and its temperature field
// unless the run is processed in probe mode — so the page shows what
// `process` will store, to the last digit. Nothing is written into the run.

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

  std::string Validate() const;  // empty when valid
};

struct LiveProbe {
  std::int64_t channel_id = 0;
  std::string name;
  cv::Point2d position_px;
  double u_px = 0, v_px = 0, shift_px = 0;
  bool valid = false;
  std::optional<double> temperature_c;  // none: not valid, no calibration nor geometry, or no temperature field
  // The sample's standard uncertainties as `process` stores them
  // (process_frame.h's probe_samples): none where not estimated.
  std::optional<double> sigma_shift_px, sigma_random_c, sigma_systematic_c;
};

struct LiveFrame {
  storage::FrameRecord frame;
  std::vector<LiveProbe> probes;
  fusion::QualityIndex quality;  // the frame against the run's reference frame
  cv::Mat thumbnail;             // CV_8U grey, at most thumbnail_width_px wide
  double decode_seconds = 0;
  double evaluate_seconds = 0;  // displacements, temperatures, quality index and thumbnail
};

class LiveProbes {
 public:
  // Reads the run's settings (as `process` resolves them), reference frame,
  // positioned channels, calibration and ambient. Throws std::runtime_error
  // saying what is missing — no reference frame yet, or no channel with an
  // image position.
  explicit LiveProbes(const std::filesystem::path& run_dir, LiveProbeOptions options = {});

  // Serialised: the evaluator behind it keeps one frame's buffers for the next.
  LiveFrame evaluate(const storage::FrameRecord& frame) const;

  const std::vector<storage::ChannelInfo>& channels() const { return channels_; }
  std::int64_t reference_frame_id() const { return reference_id_; }
  // As process_frame.h's temperature_source().
  const std::string& temperature_source() const { return temperature_source_; }
  // Seconds to add to a frame's time to put it on the thermocouples' clock.
  double camera_offset_s() const { return camera_offset_s_; }

  struct Context;  // what every frame's evaluation needs, read once (live_probes.cc)

 private:
  std::shared_ptr<Context> context_;
  std::vector<storage::ChannelInfo> channels_;
  std::int64_t reference_id_ = 0;
  std::string temperature_source_;
  double camera_offset_s_ = 0;
};

}  // namespace bosfuse::pipeline
