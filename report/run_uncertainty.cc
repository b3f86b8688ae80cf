#include "report/run_uncertainty.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>

#include "fusion/bos_geometry.h"
#include "pipeline/probe_calibration.h"
#include "pipeline/processing_settings.h"
#include "pipeline/run_selection.h"

namespace bosfuse::report {
namespace {

using json = nlohmann::json;

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// The hottest BOS probe sample with a systematic σ: the budget's basis.
struct HottestSample {
  std::optional<double> temperature_c;
  std::string probe;  // the probe's (the thermocouple's) name
  std::int64_t frame_id = 0;
};

ProbeUncertainty probe_uncertainty(const std::string& name, const std::string& probe,
                                   const std::vector<storage::ProbeSampleRecord>& samples, HottestSample& hottest) {
  ProbeUncertainty p;
  p.probe = name;
  std::vector<double> random, systematic;
  for (const auto& s : samples) {
    if (!s.valid || !s.temperature_c) continue;
    ++p.samples;
    if (s.sigma_random_c) random.push_back(*s.sigma_random_c);
    if (s.sigma_systematic_c) {
      systematic.push_back(*s.sigma_systematic_c);
      if (!hottest.temperature_c || *s.temperature_c > *hottest.temperature_c) {
        hottest = {s.temperature_c, probe, s.frame_id};
      }
    }
  }
  p.samples_with_sigma = random.size();
  if (!random.empty()) {
    p.max_random_c = *std::max_element(random.begin(), random.end());
    p.median_random_c = median(random);
  }
  if (!systematic.empty()) p.median_systematic_c = median(systematic);
  return p;
}

// k, T0, T_amb of a stored fit, with their systematic part and combined
// interval when the fit has them (pipeline/probe_fit.h's keys).
void fit_intervals(const std::string& series, const json& fit, std::vector<FitInterval>& out) {
  if (!fit.value("ok", false) || !fit.contains("parameters")) return;
  const bool in_px = fit.value("unit", "degC") == "px";
  for (const auto& [key, label, systematic_key] : {std::tuple{"k_per_s", "k", "systematic_per_s"},
                                                   {"T0_c", "T0", "systematic_c"},
                                                   {"T_amb_c", "T_amb", "systematic_c"}}) {
    const json& p = fit.at("parameters").value(key, json());
    if (!p.is_object() || !p.contains("value") || !p.at("value").is_number()) continue;
    FitInterval f;
    f.series = series;
    f.parameter = label;
    f.unit = std::string(key) == "k_per_s" ? "1/s" : (in_px ? "px" : "°C");
    f.value = p.at("value").get<double>();
    f.std_error = p.value("std_error", json()).is_number() ? p.at("std_error").get<double>() : 0.0;
    if (p.contains(systematic_key) && p.at(systematic_key).is_number())
      f.systematic = p.at(systematic_key).get<double>();
    const json& interval = p.contains("combined_interval") ? p.at("combined_interval") : p.value("interval", json());
    if (!interval.is_object() || !interval.value("low", json()).is_number()) continue;
    f.low = interval.at("low").get<double>();
    f.high = interval.at("high").get<double>();
    f.confidence = interval.value("confidence", 0.95);
    out.push_back(std::move(f));
  }
}

// The window-average correction stored with the frame's temperature field
// for `probe` (pipeline/process_frame.cc), nullopt for a processing before
// it or where none was made.
struct StoredCorrection {
  double correction_c = 0, sigma_c = 0, effective_window_px = 0;
};
std::optional<StoredCorrection> stored_correction(const storage::ProcessingStore& results, const HottestSample& h) {
  for (const auto& f : results.fields()) {
    if (f.frame_id != h.frame_id || f.kind != "temperature") continue;
    const json j = json::parse(f.json, nullptr, false);
    if (!j.is_object() || !j.contains("window_correction")) return std::nullopt;
    const json& w = j.at("window_correction");
    for (const auto& p : w.value("probes", json::array())) {
      if (p.value("probe", "") != h.probe || !p.value("correction_c", json()).is_number() ||
          !p.value("sigma_c", json()).is_number())
        continue;
      return StoredCorrection{p.at("correction_c").get<double>(), p.at("sigma_c").get<double>(),
                              w.value("effective_window_px", 0.0)};
    }
    return std::nullopt;
  }
  return std::nullopt;
}

// The budget at the hottest sample with the processing's geometry, its
// ambient resolved from the thermocouples at the reference frame as
// `process` does, with the window-average correction's σ stored for it.
void add_budget(const storage::RunStore& store, const storage::ProcessingStore& results,
                const storage::ExperimentClock& clock, const HottestSample& hottest, UncertaintySummary& u) {
  const auto processing = results.current_processing();
  if (!processing) return;
  auto settings = pipeline::settings_from_json(json::parse(processing->settings_json));
  pipeline::resolve_ambient(settings.geometry, store, pipeline::positioned_channels(store.channels()), clock,
                            pipeline::split_frames(store.frames()).reference);
  const fusion::BosGeometry geometry(settings.geometry.geometry);
  const auto correction = stored_correction(results, hottest);
  const double temperature_c = *hottest.temperature_c;
  u.budget = fusion::temperature_budget(geometry, settings.geometry.uncertainty, temperature_c,
                                        correction ? std::optional(correction->sigma_c) : std::nullopt);
  const std::string window =
      correction ? fmt::format("The sample includes the window-average correction {:+.3f} °C (−κ·∇²T, the chain "
                               "averaging as a {:.1f} px box, and the bilinear interpolation's term); the row "
                               "\"window-average correction\" is that correction's uncertainty. Each sample's stored "
                               "systematic σ holds its own",
                               correction->correction_c, correction->effective_window_px)
                 : std::string("No window-average correction is stored for this sample (a processing before it, or "
                               "a probe next to an unmeasured node): its temperature is the field's, uncorrected");
  u.budget_basis = fmt::format(
      "At {:.2f} °C, the hottest BOS probe sample ({}), in {:.2f} °C ambient air (the processing's geometry, the "
      "inputs' standard uncertainties from the run's [geometry.uncertainty]). {}",
      temperature_c, hottest.probe, settings.geometry.geometry.ambient_temperature_c, window);
}

}  // namespace

UncertaintySummary stored_uncertainty(const storage::RunStore& store, const storage::ProcessingStore& results,
                                      const storage::ExperimentClock& clock) {
  UncertaintySummary u;
  HottestSample hottest;
  std::map<std::int64_t, std::string> names;
  std::size_t with_temperature = 0, with_sigma = 0;
  for (const auto& probe : results.probes()) {
    names[probe.id] = probe.name + " (BOS)";
    u.probes.push_back(probe_uncertainty(names[probe.id], probe.name, results.probe_samples(probe.id), hottest));
    with_temperature += u.probes.back().samples;
    with_sigma += u.probes.back().samples_with_sigma;
  }
  for (const auto& f : results.fits()) {
    if (f.subject != storage::FitSubject::kProbe || !names.count(f.subject_id)) continue;
    fit_intervals(names[f.subject_id], json::parse(f.json), u.fits);
  }
  if (with_temperature > 0 && with_sigma == 0) {
    u.notes.push_back(
        "The stored BOS samples carry no uncertainty: the run was processed before they did (schema version 4), or "
        "the displacement field had no σ (optical flow, a final pass without deformation). Run bosfuse process "
        "again to estimate them.");
  }
  const bool physical_model = pipeline::stored_calibration(results).empty();
  if (hottest.temperature_c && physical_model) {
    try {
      add_budget(store, results, clock, hottest, u);
    } catch (const std::exception& e) {
      u.notes.push_back(std::string("No Type-B budget: the processing's geometry could not be read: ") + e.what());
    }
  } else if (hottest.temperature_c) {
    u.notes.push_back(
        "The BOS temperatures come from a calibration: their systematic σ is |shift| × the standard error of its "
        "slope, not the set-up's Type-B budget.");
  }
  if (u.probes.empty()) u = {};
  return u;
}

}  // namespace bosfuse::report
