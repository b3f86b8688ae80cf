#include "pipeline/run_selection.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fusion/time_alignment.h"
#include "pipeline/image_io.h"
#include "storage/run_paths.h"

namespace bosfuse::pipeline {

RunFrames split_frames(const std::vector<storage::FrameRecord>& frames) {
  RunFrames out;
  bool found = false;
  for (const auto& f : frames) {
    if (f.is_reference && !found) {
      out.reference = f;
      found = true;
    } else if (!f.is_reference) {
      out.measurements.push_back(f);
    }
  }
  if (!found) {
    throw std::runtime_error(
        "the run has " + std::to_string(frames.size()) +
        " frames but no reference frame (a frame recorded without the flow, is_reference = 1): mark one with "
        "`sqlite3 RUN/run.sqlite \"UPDATE frames SET is_reference = 1 WHERE id = ID\"` (usually the first frame, "
        "taken before the heater was switched on), or record with [[cameras]] reference_frames = N or its "
        "reference_flag file (docs/CONFIG.md)");
  }
  if (out.measurements.empty()) throw std::runtime_error("the run has no frames to evaluate besides the reference");
  return out;
}

std::string why_no_bos_evaluation(const std::vector<storage::FrameRecord>& frames) {
  if (frames.empty()) return "the run has no frames";
  const bool measured = std::any_of(frames.begin(), frames.end(), [](const auto& f) { return !f.is_reference; });
  return measured ? "" : "the run has only reference frames, none to evaluate against them";
}

std::vector<storage::ChannelInfo> positioned_channels(const std::vector<storage::ChannelInfo>& channels) {
  std::vector<storage::ChannelInfo> out;
  for (const auto& c : channels) {
    if (c.image_x_px && c.image_y_px && std::isfinite(*c.image_x_px) && std::isfinite(*c.image_y_px)) out.push_back(c);
  }
  return out;
}

std::vector<storage::ChannelInfo> fitted_channels(const std::vector<storage::ChannelInfo>& channels) {
  std::vector<storage::ChannelInfo> out;
  const auto positioned = positioned_channels(channels);
  for (const auto& c : channels) {
    const bool has_position = std::any_of(positioned.begin(), positioned.end(), [&](const auto& p) { return p.id == c.id; });
    if (c.kind == "thermocouple" || has_position) out.push_back(c);
  }
  return out;
}

TimeSeries channel_series(const storage::RunStore& store, std::int64_t channel_id,
                          const storage::ExperimentClock& clock) {
  TimeSeries s;
  for (const auto& sample : store.read_samples(channel_id)) {
    if (sample.status != storage::SampleStatus::kOk || !sample.value) continue;
    s.t_s.push_back(clock.seconds(sample.t_ns));
    s.value.push_back(*sample.value);
  }
  return s;
}

void resolve_ambient(GeometryConfig& geometry, const storage::RunStore& store,
                     const std::vector<storage::ChannelInfo>& channels, const storage::ExperimentClock& clock,
                     const storage::FrameRecord& reference) {
  if (geometry.ambient_given) return;
  const std::vector<double> at{clock.seconds(reference.t_ns) + geometry.camera_offset_s};
  double sum = 0;
  int count = 0;
  for (const auto& c : channels) {
    const TimeSeries s = channel_series(store, c.id, clock);
    const auto aligned = fusion::align_to_frames(s.t_s, s.value, at);
    if (aligned.ok(0)) sum += aligned.value[0], ++count;
  }
  if (count) geometry.geometry.ambient_temperature_c = sum / count;
}

TimeSeries within(const TimeSeries& s, double from_s, double to_s) {
  TimeSeries out;
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    if (s.t_s[i] >= from_s && s.t_s[i] <= to_s) {
      out.t_s.push_back(s.t_s[i]);
      out.value.push_back(s.value[i]);
    }
  }
  return out;
}

cv::Mat load_mask(const std::filesystem::path& run_dir, const std::string& mask) {
  if (mask.empty()) return {};
  return read_image(storage::resolve_in_run(run_dir, mask).string(), "mask");
}

cv::Mat load_frame(const std::filesystem::path& run_dir, const storage::FrameRecord& frame) {
  const std::string role = "frame " + std::to_string(frame.id);
  try {
    return read_image(storage::resolve_in_run(run_dir, frame.path).string(), role);
  } catch (const storage::StorageError& e) {
    throw std::runtime_error(role + ": " + e.what());
  }
}

}  // namespace bosfuse::pipeline
