#pragma once
// A probe's temperature from its shift by the run's newest calibration
// (`bosfuse calibrate`, calibrate.h): per channel, °C per px of shift
// magnitude around the reference temperature. `process` and the live page
// convert probe shifts the same way through this one piece.

#include <cstdint>
#include <map>
#include <optional>

#include "storage/processing_store.h"

namespace bosfuse::pipeline {

struct ChannelCalibration {
  double slope_c_per_px = 0;
  double reference_temperature_c = 0;
  double camera_offset_s = 0;  // the offset the calibration was made with
};

// By channel id; channels whose calibration failed are left out, and a run
// without a calibration gives an empty map.
std::map<std::int64_t, ChannelCalibration> stored_calibration(const storage::ProcessingStore& results);

// The calibrated temperature of a shift, nothing when the channel has no calibration.
std::optional<double> calibrated_temperature_c(const std::map<std::int64_t, ChannelCalibration>& calibration,
                                               std::int64_t channel_id, double shift_px);

}  // namespace bosfuse::pipeline
