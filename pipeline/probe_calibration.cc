#include "pipeline/probe_calibration.h"

#include <nlohmann/json.hpp>

namespace bosfuse::pipeline {

std::map<std::int64_t, ChannelCalibration> stored_calibration(const storage::ProcessingStore& results) {
  std::map<std::int64_t, ChannelCalibration> out;
  const auto record = results.latest_calibration();
  if (!record) return out;
  const auto j = nlohmann::json::parse(record->json);
  for (const auto& c : j.at("channels")) {
    if (!c.at("ok").get<bool>()) continue;
    out[c.at("channel_id").get<std::int64_t>()] = {c.at("slope_c_per_px").get<double>(),
                                                   c.at("reference_temperature_c").get<double>(),
                                                   c.value("camera_offset_s", 0.0)};
  }
  return out;
}

std::optional<double> calibrated_temperature_c(const std::map<std::int64_t, ChannelCalibration>& calibration,
                                               std::int64_t channel_id, double shift_px) {
  const auto cal = calibration.find(channel_id);
  if (cal == calibration.end()) return std::nullopt;
  return cal->second.reference_temperature_c + cal->second.slope_c_per_px * shift_px;
}

}  // namespace bosfuse::pipeline
