#include "pipeline/probe_calibration.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "storage/experiment_clock.h"

namespace bosfuse::pipeline {

bool is_cleared(const storage::CalibrationRecord& record) {
  return nlohmann::json::parse(record.json).value("kind", "") == kClearedCalibration;
}

std::map<std::int64_t, ChannelCalibration> stored_calibration(const storage::ProcessingStore& results) {
  std::map<std::int64_t, ChannelCalibration> out;
  const auto record = results.latest_calibration();
  if (!record || is_cleared(*record)) return out;
  const auto j = nlohmann::json::parse(record->json);
  for (const auto& c : j.at("channels")) {
    if (!c.at("ok").get<bool>()) continue;
    // Calibrations before the ambient anchor have none: their line starts at
    // the thermocouple's reading at the reference frame.
    const double anchor_c =
        c.contains("anchor_c") ? c.at("anchor_c").get<double>() : c.at("reference_temperature_c").get<double>();
    out[c.at("channel_id").get<std::int64_t>()] = {c.at("slope_c_per_px").get<double>(), anchor_c,
                                                   c.value("camera_offset_s", 0.0),
                                                   c.value("slope_std_error_c_per_px", 0.0),
                                                   c.value("anchor_std_error_c", 0.0)};
  }
  return out;
}

std::optional<double> calibrated_temperature_c(const std::map<std::int64_t, ChannelCalibration>& calibration,
                                               std::int64_t channel_id, double shift_px) {
  const auto cal = calibration.find(channel_id);
  if (cal == calibration.end()) return std::nullopt;
  return cal->second.reference_temperature_c + cal->second.slope_c_per_px * shift_px;
}

namespace {

// The newest calibration's usable channels, described, by channel id.
std::map<std::int64_t, std::string> calibration_descriptions(const storage::ProcessingStore& results) {
  std::map<std::int64_t, std::string> out;
  const auto record = results.latest_calibration();
  if (!record || is_cleared(*record)) return out;
  const auto j = nlohmann::json::parse(record->json);
  for (const auto& c : j.at("channels")) {
    if (!c.at("ok").get<bool>()) continue;
    std::string text = fmt::format("calibration stored {} (row {}): {:.4g} ± {:.2g} degC/px",
                                   storage::format_iso8601_utc(record->created_ns, 0), record->id,
                                   c.at("slope_c_per_px").get<double>(), c.value("slope_std_error_c_per_px", 0.0));
    if (c.value("forced", false)) {
      text += ", FORCED although it failed its checks: ";
      for (const auto& p : c.at("checks_failed")) text += p.get<std::string>() + "; ";
      text.resize(text.size() - 2);
    }
    out[c.at("channel_id").get<std::int64_t>()] = text;
  }
  return out;
}

}  // namespace

std::map<std::string, std::string> temperature_conversions(const storage::ProcessingStore& results,
                                                           const std::vector<storage::ChannelInfo>& channels,
                                                           bool physical_model) {
  const auto calibrated = calibration_descriptions(results);
  std::map<std::string, std::string> out;
  for (const auto& c : channels) {
    const auto cal = calibrated.find(c.id);
    out[c.name] = cal != calibrated.end() ? cal->second : physical_model ? "physical model" : "none: the shift in px";
  }
  return out;
}

}  // namespace bosfuse::pipeline
