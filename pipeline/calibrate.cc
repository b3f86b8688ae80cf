#include "pipeline/calibrate.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "acquisition/clock.h"
#include "fusion/calibration.h"
#include "fusion/time_alignment.h"
#include "pipeline/processing_settings.h"
#include "pipeline/run_selection.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

}  // namespace

namespace {

// The probe's valid samples on the fits' time axis (frame clock) and their shift.
struct ProbeShifts {
  std::vector<double> frame_t_s, shift_px;
};

ProbeShifts valid_shifts(const std::vector<storage::ProbeSampleRecord>& samples,
                         const storage::ExperimentClock& clock) {
  ProbeShifts out;
  for (const auto& s : samples) {
    if (!s.valid) continue;
    out.frame_t_s.push_back(clock.seconds(s.t_ns));
    out.shift_px.push_back(s.shift_px);
  }
  return out;
}

// The configured offset, or the estimate when asked for and identifiable.
double camera_offset_for(const TimeSeries& tc, const ProbeShifts& probe, double configured_s, double search_s, json& record,
                         std::string& text) {
  if (search_s <= 0) return configured_s;
  fusion::OffsetSearchOptions search;
  search.max_offset_s = search_s;
  const auto estimate = fusion::estimate_clock_offset(tc.t_s, tc.value, probe.frame_t_s, probe.shift_px, search);
  record["offset_estimate"] = {
      {"ok", estimate.ok}, {"offset_s", estimate.offset_s}, {"r2", estimate.r2}, {"message", estimate.message}};
  text += fmt::format("{}: clock offset {}\n", record["name"].get<std::string>(),
                      estimate.ok ? fmt::format("estimated {:.3f} s (r2 {:.4f})", estimate.offset_s, estimate.r2)
                                  : "not estimated: " + estimate.message);
  return estimate.ok ? estimate.offset_s : configured_s;
}

// ΔT of the thermocouple above its reading at the reference frame against
// the shift; fills `record` and returns whether a calibration was made.
bool calibrate_channel(const TimeSeries& tc, const ProbeShifts& probe, double reference_t_s, double offset_s, json& record,
                       std::string& text) {
  const std::string name = record["name"].get<std::string>();
  record["camera_offset_s"] = offset_s;
  const std::vector<double> at_reference{reference_t_s};
  const auto reference_tc = fusion::align_to_frames(tc.t_s, tc.value, at_reference, offset_s);
  if (!reference_tc.ok(0)) {
    record["ok"] = false;
    record["message"] = "the thermocouple has no reading at the reference frame's time";
    text += name + ": " + record["message"].get<std::string>() + "\n";
    return false;
  }
  const auto aligned = fusion::align_to_frames(tc.t_s, tc.value, probe.frame_t_s, offset_s);
  std::vector<double> rise;
  for (double v : aligned.value) rise.push_back(v - reference_tc.value[0]);  // NaN outside: dropped by the fit
  const auto fit = fusion::fit_linear_calibration(probe.shift_px, rise);
  record["ok"] = fit.ok;
  record["message"] = fit.message;
  record["reference_temperature_c"] = reference_tc.value[0];
  record["slope_c_per_px"] = fit.slope;
  record["slope_std_error_c_per_px"] = fit.slope_std_error;
  record["residual_rms_c"] = fit.residual_rms;
  record["points"] = fit.points;
  record["frames_outside_thermocouple_record"] = aligned.outside;
  record["shift_range_px"] = {fit.x_min, fit.x_max};
  text += name + ": " + fit.brief_report() + " (per px of shift)\n";
  return fit.ok;
}

}  // namespace

std::string calibrate_run(const fs::path& run_dir, const CalibrateOptions& options) {
  storage::ProcessingStore results(run_dir, true);
  const auto store = storage::RunStore::open(run_dir);
  const auto probes = results.probes();
  if (probes.empty()) throw std::runtime_error("the run has no BOS probe series: run `bosfuse process RUN` first");
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  const RunFrames frames = split_frames(store.frames());
  SettingsOverrides geometry;
  if (!options.geometry_file.empty()) geometry.geometry_file = options.geometry_file;
  const double configured_offset_s =
      options.camera_offset_s.value_or(resolve_settings(run_dir, geometry).geometry.camera_offset_s);
  const double reference_t_s = clock.seconds(frames.reference.t_ns);
  json channels = json::array();
  std::string text;
  std::size_t calibrated = 0;
  for (const auto& probe : probes) {
    if (!probe.channel_id) continue;
    json record = {{"channel_id", *probe.channel_id}, {"probe_id", probe.id}, {"name", probe.name}};
    const TimeSeries tc = channel_series(store, *probe.channel_id, clock);
    const ProbeShifts shifts = valid_shifts(results.probe_samples(probe.id), clock);
    const double offset_s =
        camera_offset_for(tc, shifts, configured_offset_s, options.estimate_offset_max_s, record, text);
    calibrated += calibrate_channel(tc, shifts, reference_t_s, offset_s, record, text) ? 1 : 0;
    channels.push_back(record);
  }
  if (calibrated == 0) throw std::runtime_error("no thermocouple could be calibrated:\n" + text);
  const json j = {{"kind", "celsius_per_px_shift"},
                  {"model", "T = T_tc(reference frame) + slope * |shift|, least squares through the origin"},
                  {"uncertainty", "standard, scaled by the residual variance"},
                  {"channels", channels}};
  results.add_calibration({0, acquisition::utc_now_ns(), j.dump()});
  return text + fmt::format("stored a calibration for {} thermocouple(s); `bosfuse process` now uses it\n", calibrated);
}

}  // namespace bosfuse::pipeline
