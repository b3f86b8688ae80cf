#pragma once
// A probe's temperature from its shift by the run's newest calibration
// (`bosfuse calibrate`, calibrate.h): per channel, °C per px of shift
// magnitude from the calibration's anchor (the ambient). `process` and the
// live page convert probe shifts the same way through this one piece.
//
// The calibrations table is a history: a new calibration is a new row, and
// `calibrate --clear` adds a row of kind "cleared", after which the run has
// no calibration (the physical model converts again) until the next one.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "storage/processing_store.h"
#include "storage/records.h"

namespace bosfuse::pipeline {

inline constexpr const char* kClearedCalibration = "cleared";

struct ChannelCalibration {
  double slope_c_per_px = 0;
  double reference_temperature_c = 0;  // the line's anchor, where the shift is 0 (calibrate.h: the ambient)
  double camera_offset_s = 0;  // the offset the calibration was made with
  double slope_std_error_c_per_px = 0;  // its standard uncertainty; 0: not stated
  double anchor_std_error_c = 0;        // the anchor's standard uncertainty (the ambient's); 0: not stated
};

// Whether the record is a `calibrate --clear` marker.
bool is_cleared(const storage::CalibrationRecord& record);

// By channel id; channels whose calibration failed are left out, and a run
// without a calibration (or whose newest record is a clear) gives an empty map.
std::map<std::int64_t, ChannelCalibration> stored_calibration(const storage::ProcessingStore& results);

// The calibrated temperature of a shift, nothing when the channel has no calibration.
std::optional<double> calibrated_temperature_c(const std::map<std::int64_t, ChannelCalibration>& calibration,
                                               std::int64_t channel_id, double shift_px);

// Which conversion gives each channel's BOS temperatures, by channel name:
// "calibration stored <UTC time> (row <id>): <slope> ± <σ> degC/px[, FORCED: ...]",
// else "physical model" when `physical_model` (full fields), else
// "none: the shift in px". Stored with a processing, shown by the report.
std::map<std::string, std::string> temperature_conversions(const storage::ProcessingStore& results,
                                                           const std::vector<storage::ChannelInfo>& channels,
                                                           bool physical_model);

}  // namespace bosfuse::pipeline
