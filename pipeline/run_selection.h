#pragma once
// What of a run a processing works on, chosen one way for every command:
// the reference frame (the first with is_reference = 1) and the frames
// measured against it, in time order; the channels with an image position
// (where BOS probes go) and those fitted with Newton's law; a channel's ok
// samples as a series in experiment seconds.

#include <filesystem>
#include <opencv2/core.hpp>
#include <vector>

#include "pipeline/geometry_config.h"
#include "storage/experiment_clock.h"
#include "storage/records.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {

struct RunFrames {
  storage::FrameRecord reference;
  std::vector<storage::FrameRecord> measurements;  // in time order
};

// Throws when the run has no reference frame (saying how to mark one) or
// nothing to evaluate.
RunFrames split_frames(const std::vector<storage::FrameRecord>& frames);

// Why a run's frames give BOS nothing to evaluate, in words ("the run has
// no frames"); empty when they do. A run with frames but no reference frame
// is not such a run: split_frames refuses it.
std::string why_no_bos_evaluation(const std::vector<storage::FrameRecord>& frames);

// Channels (any kind) with a finite position in the image.
std::vector<storage::ChannelInfo> positioned_channels(const std::vector<storage::ChannelInfo>& channels);

// Thermocouple channels and positioned ones: those a processing fits.
std::vector<storage::ChannelInfo> fitted_channels(const std::vector<storage::ChannelInfo>& channels);

struct TimeSeries {
  std::vector<double> t_s, value;
};

// The channel's ok samples, times in experiment seconds.
TimeSeries channel_series(const storage::RunStore& store, std::int64_t channel_id,
                          const storage::ExperimentClock& clock);

// The physical model's ambient when the geometry does not give one: the
// channels' mean reading (each interpolated) at the reference frame, taken
// without the flow, on the thermocouples' clock (frame time plus the
// geometry's camera offset). Left as it is when the geometry gives it, or
// when no channel has a value there.
void resolve_ambient(GeometryConfig& geometry, const storage::RunStore& store,
                     const std::vector<storage::ChannelInfo>& channels, const storage::ExperimentClock& clock,
                     const storage::FrameRecord& reference);

// The part of `s` with from_s ≤ t ≤ to_s.
TimeSeries within(const TimeSeries& s, double from_s, double to_s);

// The settings' mask (a file in the run folder, relative to it); an empty
// image when they name none.
cv::Mat load_mask(const std::filesystem::path& run_dir, const std::string& mask);

// A frame's image; a frame the run cannot deliver (missing, unreadable, or
// a stored path leading outside the run) throws, naming the frame.
cv::Mat load_frame(const std::filesystem::path& run_dir, const storage::FrameRecord& frame);

}  // namespace bosfuse::pipeline
