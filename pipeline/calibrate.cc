#include "pipeline/calibrate.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "acquisition/clock.h"
#include "fusion/time_alignment.h"
#include "pipeline/probe_calibration.h"
#include "pipeline/processing_settings.h"
#include "pipeline/run_selection.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

constexpr double kLeastReferenceToleranceS = 0.25;

// The probe's valid samples on the fits' time axis (frame clock) and their shift.
struct ProbeShifts {
  std::vector<double> frame_t_s, shift_px;
  std::vector<double> sigma_px;  // the shift's σ per sample when stored; empty: not estimated
};

ProbeShifts valid_shifts(const std::vector<storage::ProbeSampleRecord>& samples,
                         const storage::ExperimentClock& clock) {
  ProbeShifts out;
  bool every_sigma = true;
  for (const auto& s : samples) {
    if (!s.valid) continue;
    out.frame_t_s.push_back(clock.seconds(s.t_ns));
    out.shift_px.push_back(s.shift_px);
    every_sigma = every_sigma && s.sigma_shift_px.has_value();
    if (s.sigma_shift_px) out.sigma_px.push_back(*s.sigma_shift_px);
  }
  // A series partly without σ (samples stored before σ, or not estimated)
  // says nothing per sample: the checks' floor stands for all of it.
  if (!every_sigma) out.sigma_px.clear();
  return out;
}

// The configured offset, or the estimate when asked for and identifiable.
double camera_offset_for(const TimeSeries& tc, const ProbeShifts& probe, double configured_s, double search_s,
                         json& record, std::string& text) {
  if (search_s <= 0) return configured_s;
  fusion::OffsetSearchOptions search;
  search.max_offset_s = search_s;
  const auto e = fusion::estimate_clock_offset(tc.t_s, tc.value, probe.frame_t_s, probe.shift_px, search);
  record["offset_estimate"] = {{"ok", e.ok},
                               {"offset_s", e.offset_s},
                               {"offset_std_s", e.offset_std_s},
                               {"r2", e.r2},
                               {"search_s", search_s},
                               {"wide_search_s", e.wide_search_s},
                               {"wide_offset_s", e.wide_offset_s},
                               {"message", e.message}};
  text += fmt::format("{}: clock offset {}\n", record["name"].get<std::string>(),
                      e.ok ? fmt::format("estimated {:.3f} ± {:.2g} s (r2 {:.4f}; the same over ±{:g} s)", e.offset_s,
                                         e.offset_std_s, e.r2, e.wide_search_s)
                           : fmt::format("not estimated: {}; the configured {:g} s is used", e.message, configured_s));
  return e.ok ? e.offset_s : configured_s;
}

double median_period_s(const std::vector<double>& t_s) {
  std::vector<double> gaps;
  for (std::size_t i = 1; i < t_s.size(); ++i) gaps.push_back(t_s[i] - t_s[i - 1]);
  if (gaps.empty()) return 0;
  const auto middle = gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2);
  std::nth_element(gaps.begin(), middle, gaps.end());
  return *middle;
}

struct ReferenceReading {
  bool ok = false;
  double value_c = 0;
  std::string how;  // interpolated, or the nearest reading and how far; or why none
};

// The thermocouple at host time t_s (the reference frame's time plus the offset).
ReferenceReading reading_at(const TimeSeries& tc, double t_s, double tolerance_s) {
  const std::vector<double> at{t_s};
  const auto inside = fusion::align_to_frames(tc.t_s, tc.value, at);
  if (inside.ok(0)) return {true, inside.value[0], "interpolated between the readings around it"};
  if (tc.t_s.empty()) return {false, 0, "the thermocouple has no readings"};
  const double tolerance =
      tolerance_s > 0 ? tolerance_s : std::max(2 * median_period_s(tc.t_s), kLeastReferenceToleranceS);
  const bool before = t_s < tc.t_s.front();
  const double gap = before ? tc.t_s.front() - t_s : t_s - tc.t_s.back();
  if (gap > tolerance) {
    return {false, 0,
            fmt::format("the thermocouple has no reading within {:.3g} s of the reference frame's time (the nearest is "
                        "{:.3g} s {})",
                        tolerance, gap, before ? "after it" : "before it")};
  }
  return {true, before ? tc.value.front() : tc.value.back(),
          fmt::format("the nearest reading, {:.3g} s {} the reference frame (tolerance {:.3g} s)", gap,
                      before ? "after" : "before", tolerance)};
}

struct ChannelResult {
  bool fitted = false;  // a fit was made
  std::vector<std::string> problems;
};

// The temperature the calibration line starts from, where BOS sees no
// shift: the reference image's air. The geometry's ambient when it states
// one (the physics conversion's Poisson boundary, fusion/bos_geometry.h);
// else, as the physics conversion then does, the thermocouple's own reading
// at the reference frame, the room taken as still and at ambient.
struct Anchor {
  bool from_ambient = false;
  double value_c = 0;
  double std_error_c = 0;  // the ambient's σ ([geometry.uncertainty]); 0 for a reading
  std::string source;
};

Anchor ambient_anchor(const GeometryConfig& geometry) {
  if (!geometry.ambient_given) return {};
  return {true, geometry.geometry.ambient_temperature_c, geometry.uncertainty.ambient_temperature_c,
          fmt::format("the ambient_temperature_c of the geometry ({})", geometry.source)};
}

void record_fit(const fusion::LinearCalibration& fit, const fusion::ShiftUncertainty& shift, std::size_t outside,
                json& record) {
  record["slope_c_per_px"] = fit.slope;
  record["slope_std_error_c_per_px"] = fit.slope_std_error;
  record["residual_rms_c"] = fit.residual_rms;
  record["r2"] = std::isfinite(fit.r2) ? json(fit.r2) : json(nullptr);
  record["points"] = fit.points;
  record["frames_outside_thermocouple_record"] = outside;
  record["shift_range_px"] = {fit.x_min, fit.x_max};
  record["shift_uncertainty_px"] = shift.sigma_px;
  record["shift_uncertainty_source"] = shift.source;
}

// The thermocouple at the reference frame against the ambient anchor: a
// difference beyond the tolerance means the reference image was not taken
// at ambient, or the thermocouple is not where the image is undisturbed.
// Not a refusal: BOS measures from the reference image, whatever the
// thermocouple read then. Empty when within the tolerance.
std::string check_reference_reading(const ReferenceReading& reading, const Anchor& anchor, double sigmas,
                                    json& record) {
  const double tolerance_c = sigmas * anchor.std_error_c;
  json check = {{"tolerance_c", tolerance_c}, {"tolerance", fmt::format("{:g} x the ambient's sigma", sigmas)}};
  std::string warning;
  if (!reading.ok) {
    check["checked"] = false;
    check["message"] = "not checked: " + reading.how;
  } else {
    const double difference = reading.value_c - anchor.value_c;
    check["checked"] = true;
    check["thermocouple_c"] = reading.value_c;
    check["difference_c"] = difference;
    check["within_tolerance"] = std::abs(difference) <= tolerance_c;
    if (std::abs(difference) > tolerance_c) {
      warning = fmt::format(
          "the thermocouple read {:.2f} degC at the reference frame, {:+.2f} degC from the ambient {:.2f} degC "
          "(tolerance {:.2g} degC, {:g} x its sigma): the reference image was not taken at ambient, or the "
          "thermocouple is not where the image is undisturbed",
          reading.value_c, difference, anchor.value_c, tolerance_c, sigmas);
    }
    check["message"] = warning.empty() ? "within the tolerance" : warning;
  }
  record["reference_check"] = check;
  return warning;
}

// ΔT of the thermocouple above the anchor against the shift; fills `record`
// (ok: usable, checked or forced).
ChannelResult calibrate_channel(const TimeSeries& tc, const ProbeShifts& probe, double reference_t_s, double offset_s,
                                const Anchor& ambient, const CalibrateOptions& options, json& record,
                                std::string& text) {
  const std::string name = record["name"].get<std::string>();
  record["camera_offset_s"] = offset_s;
  const ReferenceReading reference = reading_at(tc, reference_t_s + offset_s, options.reference_tolerance_s);
  record["reference_reading"] = reference.how;
  if (reference.ok) record["reference_temperature_c"] = reference.value_c;
  ChannelResult result;
  if (!ambient.from_ambient && !reference.ok) {
    record["ok"] = false;
    record["message"] = reference.how + " (and the geometry states no ambient_temperature_c to anchor to)";
    result.problems.push_back(record["message"].get<std::string>());
    text += name + ": " + record["message"].get<std::string>() + "\n";
    return result;
  }
  const Anchor anchor =
      ambient.from_ambient
          ? ambient
          : Anchor{false, reference.value_c, 0,
                   "the thermocouple's reading at the reference frame (the geometry states no ambient_temperature_c)"};
  record["anchor_c"] = anchor.value_c;
  record["anchor_std_error_c"] = anchor.std_error_c;
  record["anchor_source"] = anchor.source;
  const std::string warning =
      anchor.from_ambient ? check_reference_reading(reference, anchor, options.ambient_check_sigmas, record) : "";
  const auto aligned = fusion::align_to_frames(tc.t_s, tc.value, probe.frame_t_s, offset_s);
  std::vector<double> rise;
  for (double v : aligned.value) rise.push_back(v - anchor.value_c);  // NaN outside: dropped by the fit
  const auto fit = fusion::fit_linear_calibration(probe.shift_px, rise);
  const auto shift = fusion::shift_uncertainty(probe.sigma_px, options.checks);
  result.fitted = fit.ok;
  result.problems = fusion::calibration_problems(fit, shift, options.checks);
  record["ok"] = fit.ok && (result.problems.empty() || options.force);
  record["message"] = fit.message;
  record_fit(fit, shift, aligned.outside, record);
  record["checks_failed"] = result.problems;
  record["forced"] = fit.ok && !result.problems.empty() && options.force;
  text += fmt::format(
      "{}: {} (per px of shift), anchored at {:.2f} ± {:.2g} degC, {}; the reference frame's reading: "
      "{}\n",
      name, fit.brief_report(), anchor.value_c, anchor.std_error_c, anchor.source, reference.how);
  if (!warning.empty()) text += name + ": note: " + warning + "\n";
  return result;
}

json checks_json(const fusion::CalibrationChecks& c) {
  return {{"min_points", c.min_points},
          {"min_r2", c.min_r2},
          {"max_residual_rms_c", c.max_residual_rms_c},
          {"min_shift_range_sigmas", c.min_shift_range_sigmas},
          {"shift_noise_floor_px", c.shift_noise_floor_px},
          {"expected_sign", c.expected_sign}};
}

}  // namespace

std::string CalibrateOptions::Validate() const {
  if (const auto problem = checks.Validate(); !problem.empty()) return problem;
  if (!(std::isfinite(reference_tolerance_s) && reference_tolerance_s >= 0)) {
    return "reference_tolerance_s must be finite and non-negative (0: automatic)";
  }
  if (!(std::isfinite(estimate_offset_max_s) && estimate_offset_max_s >= 0)) {
    return "estimate_offset_max_s must be finite and non-negative";
  }
  if (!(std::isfinite(ambient_check_sigmas) && ambient_check_sigmas >= 0)) {
    return "ambient_check_sigmas must be finite and non-negative";
  }
  return {};
}

CalibrationOutcome calibrate_run(const fs::path& run_dir, const CalibrateOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  storage::ProcessingStore results(run_dir, true);
  const auto store = storage::RunStore::open(run_dir);
  if (const std::string why = why_no_bos_evaluation(store.frames()); !why.empty()) {
    throw std::runtime_error(why + ": a calibration compares BOS probes with the thermocouples, so it needs a "
                                   "camera's frames (the thermocouples' fits are `bosfuse process RUN`'s)");
  }
  const auto probes = results.probes();
  if (probes.empty()) throw std::runtime_error("the run has no BOS probe series: run `bosfuse process RUN` first");
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  const RunFrames frames = split_frames(store.frames());
  SettingsOverrides geometry;
  if (!options.geometry_file.empty()) geometry.geometry_file = options.geometry_file;
  const GeometryConfig settings = resolve_settings(run_dir, geometry).geometry;
  const double configured_offset_s = options.camera_offset_s.value_or(settings.camera_offset_s);
  const Anchor ambient = ambient_anchor(settings);
  const double reference_t_s = clock.seconds(frames.reference.t_ns);
  json channels = json::array();
  CalibrationOutcome outcome;
  std::size_t fitted = 0;
  for (const auto& probe : probes) {
    if (!probe.channel_id) continue;
    json record = {{"channel_id", *probe.channel_id}, {"probe_id", probe.id}, {"name", probe.name}};
    const TimeSeries tc = channel_series(store, *probe.channel_id, clock);
    const ProbeShifts shifts = valid_shifts(results.probe_samples(probe.id), clock);
    const double offset_s =
        camera_offset_for(tc, shifts, configured_offset_s, options.estimate_offset_max_s, record, outcome.text);
    const ChannelResult r =
        calibrate_channel(tc, shifts, reference_t_s, offset_s, ambient, options, record, outcome.text);
    fitted += r.fitted ? 1 : 0;
    for (const auto& p : r.problems) outcome.problems.push_back(probe.name + ": " + p);
    channels.push_back(record);
  }
  const bool refused = fitted == 0 || (!outcome.problems.empty() && !options.force);
  if (refused) {
    outcome.text += fitted == 0 ? "no thermocouple could be calibrated: nothing stored\n"
                                : "calibration refused: nothing stored (`--force` stores it anyway); the run keeps "
                                  "its earlier conversion\n";
    return outcome;
  }
  const json j = {
      {"kind", "celsius_per_px_shift"},
      {"model",
       "T = anchor_c + slope * |shift|, least squares through the origin; anchor_c: the geometry's "
       "ambient, else the thermocouple at the reference frame"},
      {"uncertainty", "standard: the slope's scaled by the residual variance, the anchor's the ambient's sigma"},
      {"forced", !outcome.problems.empty()},
      {"checks", checks_json(options.checks)},
      {"channels", channels}};
  results.add_calibration({0, acquisition::utc_now_ns(), j.dump()});
  outcome.stored = true;
  outcome.text += fmt::format("stored a {}calibration for {} thermocouple(s); `bosfuse process` now uses it\n",
                              outcome.problems.empty() ? "" : "FORCED ", fitted);
  return outcome;
}

std::string clear_calibration(const fs::path& run_dir) {
  storage::ProcessingStore results(run_dir, true);
  const auto latest = results.latest_calibration();
  if (!latest || is_cleared(*latest)) {
    return "the run has no calibration: nothing to clear; `bosfuse process` uses the physical model\n";
  }
  const json j = {{"kind", kClearedCalibration},
                  {"cleared_calibration_id", latest->id},
                  {"cleared_created_ns", latest->created_ns}};
  results.add_calibration({0, acquisition::utc_now_ns(), j.dump()});
  return fmt::format(
      "cleared the calibration stored {} (calibrations row {}, kept as history); the next `bosfuse process` uses "
      "the physical model (full fields) or the shift (probe mode)\n",
      storage::format_iso8601_utc(latest->created_ns, 3), latest->id);
}

}  // namespace bosfuse::pipeline
