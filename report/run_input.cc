#include "report/run_input.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "fitting/fit_json.h"
#include "pipeline/field_csv.h"
#include "pipeline/process.h"
#include "pipeline/processing_settings.h"
#include "pipeline/quality_json.h"
#include "pipeline/run_selection.h"
#include "report/run_uncertainty.h"
#include "storage/experiment_clock.h"
#include "storage/processing_store.h"
#include "storage/run_paths.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

using json = nlohmann::json;

// A fit stored by `bosfuse process`, its origin on the report's clock (a
// fit stored before version 4 has its own origin, on the same scale). No
// residuals are stored.
fitting::NewtonFit stored_fit(const storage::FitRecord& record, const storage::ExperimentClock& clock) {
  fitting::NewtonFit fit = fitting::fit_from_json(json::parse(record.json));
  fit.origin_s = clock.seconds(record.origin_t_ns);
  return fit;
}

// A stored field (pipeline/field_csv.h) as a map on its grid: `value` at the
// nodes where `measured` is non-zero and finite; NaN and masked elsewhere, so
// that no value the solve filled in (or a replaced outlier's neighbour median)
// reaches a map's CSV, figure or contours as if it were a measurement.
MapField map_from_stored(const pipeline::StoredFieldGrid& grid, const cv::Mat& value, const cv::Mat& measured) {
  MapField map;
  map.values = cv::Mat(grid.rows(), grid.cols(), CV_64F, cv::Scalar(std::numeric_limits<double>::quiet_NaN()));
  map.mask = cv::Mat(grid.rows(), grid.cols(), CV_8U, cv::Scalar(255));
  map.x0_px = grid.x_px.front();
  map.y0_px = grid.y_px.front();
  map.step_px = grid.cols() > 1 ? grid.x_px[1] - grid.x_px[0] : (grid.rows() > 1 ? grid.y_px[1] - grid.y_px[0] : 1.0);
  for (int r = 0; r < grid.rows(); ++r) {
    for (int c = 0; c < grid.cols(); ++c) {
      const double v = value.at<double>(r, c);
      const double m = measured.at<double>(r, c);
      if (!grid.present.at<std::uint8_t>(r, c) || !std::isfinite(v) || !std::isfinite(m) || m == 0) continue;
      map.values.at<double>(r, c) = v;
      map.mask.at<std::uint8_t>(r, c) = 0;
    }
  }
  return map;
}

// Nodes the solve filled in (`measured` 0: masked, no texture, no peak) and
// unphysical ones (no temperature) are not measurements.
MapField read_temperature_csv(const fs::path& path) {
  const auto grid = pipeline::read_stored_field(path, pipeline::kTemperatureColumns);
  MapField map = map_from_stored(grid, grid.column("temperature_c"), grid.column("measured"));
  map.quantity = "temperature";
  map.unit = "°C";
  return map;
}

// `valid` is 1 for kOk vectors only: a replaced outlier is not shown either.
MapField read_displacement_csv(const fs::path& path) {
  const auto grid = pipeline::read_stored_field(path, pipeline::kDisplacementColumns);
  cv::Mat magnitude;
  cv::magnitude(grid.column("u"), grid.column("v"), magnitude);
  MapField map = map_from_stored(grid, magnitude, grid.column("valid"));
  map.quantity = "|displacement|";
  map.unit = "px";
  return map;
}

// Everything a run's processing stored, read into the report.
struct StoredReader {
  const storage::RunStore& store;
  const storage::ProcessingStore* results;  // null: none could be read
  const storage::ExperimentClock& clock;
  const RunReportOptions& options;
  ReportInput& input;

  std::map<std::int64_t, storage::FitRecord> fits(storage::FitSubject subject) const {
    std::map<std::int64_t, storage::FitRecord> out;
    if (!results) return out;
    for (const auto& f : results->fits()) {
      if (f.subject == subject) out[f.subject_id] = f;
    }
    return out;
  }

  void attach_fit(CurveSeries& s, const std::map<std::int64_t, storage::FitRecord>& fits, std::int64_t id) const {
    const auto f = fits.find(id);
    if (f == fits.end()) return;
    try {
      s.fit = stored_fit(f->second, clock);
    } catch (const std::exception& e) {
      input.notes.push_back(fmt::format("The stored fit of {} could not be read: {}", s.name, e.what()));
    }
  }

  void thermocouples() const {
    const auto channel_fits = fits(storage::FitSubject::kChannel);
    for (const auto& channel : store.channels()) {
      if (channel.kind != "thermocouple" && !channel_fits.count(channel.id)) continue;
      CurveSeries s;
      s.name = channel.name;
      s.kind = SeriesKind::kThermocouple;
      if (channel.image_x_px && channel.image_y_px) s.image_px = cv::Point2d(*channel.image_x_px, *channel.image_y_px);
      for (const auto& sample : store.read_samples(channel.id)) {
        if (sample.status != storage::SampleStatus::kOk || !sample.value) {
          ++s.excluded_samples;
          continue;
        }
        s.time_s.push_back(clock.seconds(sample.t_ns));
        s.temperature_c.push_back(*sample.value);
      }
      attach_fit(s, channel_fits, channel.id);
      input.series.push_back(std::move(s));
    }
    if (input.series.empty()) input.notes.push_back("The run has no thermocouple channels.");
  }

  std::map<std::int64_t, std::string> probes() const {
    const auto probe_fits = fits(storage::FitSubject::kProbe);
    std::map<std::int64_t, std::string> names;
    bool any_shift = false;
    for (const auto& probe : results->probes()) {
      CurveSeries s;
      s.name = probe.name + " (BOS)";
      names[probe.id] = s.name;
      s.kind = SeriesKind::kBosProbe;
      s.image_px = cv::Point2d(probe.x_px, probe.y_px);
      const auto samples = results->probe_samples(probe.id);
      const bool has_temperature =
          std::any_of(samples.begin(), samples.end(), [](const auto& p) { return p.valid && p.temperature_c; });
      any_shift = any_shift || !has_temperature;
      if (!has_temperature) s.unit = "px";
      for (const auto& p : samples) {
        const std::optional<double> value = has_temperature ? p.temperature_c : std::optional<double>(p.shift_px);
        if (!p.valid || !value || !std::isfinite(*value)) {
          ++s.excluded_samples;
          continue;
        }
        s.time_s.push_back(clock.seconds(p.t_ns));
        s.temperature_c.push_back(*value);
      }
      attach_fit(s, probe_fits, probe.id);
      input.series.push_back(std::move(s));
    }
    if (any_shift) {
      input.notes.push_back(
          "Some BOS probes have no temperature (no calibration): their series are the shift magnitude in px, not °C "
          "(run bosfuse calibrate, then bosfuse process).");
    }
    return names;
  }

  void agreements(const std::map<std::int64_t, std::string>& probe_names) const {
    std::map<std::int64_t, std::string> channel_names;
    for (const auto& c : store.channels()) channel_names[c.id] = c.name;
    for (const auto& a : results->agreements()) {
      try {
        AgreementEntry entry;
        const auto tc = channel_names.find(a.channel_id);
        const auto probe = probe_names.find(a.probe_id);
        entry.thermocouple = tc != channel_names.end() ? tc->second : fmt::format("channel {}", a.channel_id);
        entry.probe = probe != probe_names.end() ? probe->second : fmt::format("probe {}", a.probe_id);
        entry.agreement = fitting::agreement_from_json(json::parse(a.json));
        input.agreements.push_back(std::move(entry));
      } catch (const std::exception& e) {
        input.notes.push_back(fmt::format("A stored agreement could not be read: {}", e.what()));
      }
    }
  }

  // The stored field files nearest the requested times, as maps.
  void maps(const std::string& kind, std::vector<MapField>& out) const {
    std::map<std::int64_t, storage::FrameRecord> frame_by_id;
    for (const auto& f : store.frames()) frame_by_id[f.id] = f;
    std::vector<std::pair<storage::FieldRecord, double>> candidates;  // field, frame time
    for (const auto& f : results->fields()) {
      const auto frame = frame_by_id.find(f.frame_id);
      if (f.kind == kind && frame != frame_by_id.end()) candidates.emplace_back(f, clock.seconds(frame->second.t_ns));
    }
    if (candidates.empty()) return;
    const cv::Size image_size(frame_by_id.begin()->second.width_px, frame_by_id.begin()->second.height_px);
    std::set<std::int64_t> done;
    for (double t : options.map_times_s) {
      const auto nearest = std::min_element(candidates.begin(), candidates.end(), [&](const auto& a, const auto& b) {
        return std::abs(a.second - t) < std::abs(b.second - t);
      });
      if (!done.insert(nearest->first.frame_id).second) continue;
      try {
        const fs::path path = storage::resolve_in_run(store.dir(), nearest->first.path);
        MapField map = kind == "temperature" ? read_temperature_csv(path) : read_displacement_csv(path);
        map.time_s = nearest->second;
        map.image_size_px = image_size;
        map.source = fmt::format("stored {} field of frame {} ({}), nearest to the requested t = {:g} s", kind,
                                 nearest->first.frame_id, nearest->first.path, t);
        out.push_back(std::move(map));
      } catch (const std::exception& e) {
        input.notes.push_back(fmt::format("No stored {} map at t = {:.1f} s: {}", kind, nearest->second, e.what()));
      }
    }
  }
};

// What a run without stored results is told: to process it, or, when its
// last processing failed, what failed (processing again would only repeat it).
void not_processed_note(const storage::ProcessingStore& results, const fs::path& run_dir, ReportInput& input) {
  const auto last = results.latest_processing();
  const std::string failure = last && last->status == "abandoned" ? pipeline::processing_failure(*last) : "";
  if (failure.empty()) {
    input.notes.push_back(fmt::format(
        "The run is not processed yet: no fits, BOS probes or maps are stored. Run `bosfuse process {}`, then "
        "this report again.",
        run_dir.string()));
    return;
  }
  input.bos_missing = fmt::format("Not processed: processing {} failed: {}", last->id, failure);
  input.notes.push_back(fmt::format(
      "The run is not processed: processing {} failed: {}. Once that is fixed, `bosfuse process {}` processes it, "
      "then make this report again.",
      last->id, failure, run_dir.string()));
}

// A processing newer than the results shown: one that failed says what
// failed, one under way or interrupted that `--resume` completes it.
void later_processing_note(const storage::ProcessingRecord& later, const fs::path& run_dir, ReportInput& input) {
  const std::string failure = pipeline::processing_failure(later);
  if (later.status == "running" && failure.empty()) {
    input.notes.push_back(fmt::format(
        "A later processing ({}) was interrupted; its partial results are not shown. `bosfuse process {} --resume` "
        "completes it.",
        later.id, run_dir.string()));
  } else if (later.status == "running") {
    input.notes.push_back(fmt::format(
        "A later processing ({}) failed at a frame: {}. Its partial results are not shown; once that is fixed, "
        "`bosfuse process {} --resume` continues it from that frame.",
        later.id, failure, run_dir.string()));
  } else if (!failure.empty()) {
    input.notes.push_back(fmt::format(
        "A later processing ({}) failed: {}. The results shown are the earlier processing's.", later.id, failure));
  }
}

// What the processing found and with which settings, from its stored row.
void processing_record(const storage::ProcessingRecord& p, ReportInput& input) {
  const auto summary = json::parse(p.summary_json);
  if (summary.contains("thermocouples_only")) {
    input.notes.push_back(fmt::format("Processed on {} (processing {}): thermocouple fits only ({}).",
                                      storage::format_iso8601_utc(p.started_ns, 0), p.id,
                                      summary.at("thermocouples_only").get<std::string>()));
    return;
  }
  if (summary.contains("quality")) {
    const auto& q = summary.at("quality");
    QualityInfo quality;
    quality.index = pipeline::quality_from_json(q);
    quality.compared = fmt::format("Last frame {} (t = {:.1f} s) against reference frame {}",
                                   q.at("frame_id").get<std::int64_t>(), q.at("t_s").get<double>(),
                                   q.at("reference_frame_id").get<std::int64_t>());
    input.quality = quality;
  }
  // Which conversion made each BOS temperature (processings before it say one for the run).
  if (summary.contains("temperature_conversions")) {
    std::string text;
    for (const auto& [probe, how] : summary.at("temperature_conversions").items()) {
      text += fmt::format("{}{} (BOS) by {}", text.empty() ? "" : "; ", probe, how.get<std::string>());
    }
    if (!text.empty()) input.notes.push_back("BOS temperatures: " + text + ".");
  } else if (summary.contains("temperature_source")) {
    input.notes.push_back("BOS temperatures from " + summary.at("temperature_source").get<std::string>() + ".");
  }
  const auto settings = pipeline::settings_from_json(json::parse(p.settings_json));
  input.notes.push_back(fmt::format("Processed on {} (processing {}): {}.", storage::format_iso8601_utc(p.started_ns, 0),
                                    p.id, pipeline::describe(settings)));
}

}  // namespace

MapField displacement_magnitude_map(const fusion::DisplacementField& field, cv::Size image_size_px) {
  if (field.rows <= 0 || field.cols <= 0 || field.size() != static_cast<std::size_t>(field.rows) * field.cols) {
    throw std::invalid_argument("the displacement field has no grid to map");
  }
  MapField map;
  map.quantity = "|displacement|";
  map.unit = "px";
  map.values = cv::Mat(field.rows, field.cols, CV_64F);
  map.u_px = cv::Mat(field.rows, field.cols, CV_64F);
  map.v_px = cv::Mat(field.rows, field.cols, CV_64F);
  map.mask = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& v = field.at(r, c);
      // Only kOk is a measurement of its own window, as the stored field's `valid` says: a replaced outlier
      // holds its neighbours' median (docs/REPORT.md, "Not measured").
      const bool shown = v.valid();
      map.values.at<double>(r, c) = shown ? std::hypot(v.u_px, v.v_px) : kNaN;
      map.u_px.at<double>(r, c) = shown ? v.u_px : kNaN;
      map.v_px.at<double>(r, c) = shown ? v.v_px : kNaN;
      map.mask.at<std::uint8_t>(r, c) = shown ? 0 : 255;
    }
  }
  map.x0_px = field.at(0, 0).x_px;
  map.y0_px = field.at(0, 0).y_px;
  if (field.cols > 1) {
    map.step_px = field.at(0, 1).x_px - field.at(0, 0).x_px;
  } else if (field.rows > 1) {
    map.step_px = field.at(1, 0).y_px - field.at(0, 0).y_px;
  }
  if (!(map.step_px > 0)) map.step_px = 1;
  map.image_size_px = image_size_px;
  return map;
}

ReportInput build_report_input(const storage::RunStore& store, const RunReportOptions& options) {
  ReportInput input;
  const auto run = store.run();
  input.run_name = run.name;
  input.run_dir = store.dir().string();
  input.started_utc = storage::format_iso8601_utc(run.started_ns, 3);
  input.status = std::string(storage::to_string(run.status));
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  input.time_basis = clock.basis();
  if (!clock.note.empty()) input.notes.push_back("Time: " + clock.note + ".");
  input.px_per_mm = options.px_per_mm;
  try {
    if (!input.px_per_mm) input.px_per_mm = pipeline::stored_px_per_mm(store.dir());
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("Map axes in px: the run's geometry could not be read: ") + e.what());
  }

  input.thermocouples_only = pipeline::why_no_bos_evaluation(store.frames());
  std::optional<storage::ProcessingStore> results;
  try {
    results.emplace(store.dir());
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("Stored processing results could not be read: ") + e.what());
  }
  const StoredReader reader{store, results ? &*results : nullptr, clock, options, input};
  if (!results) {
    reader.thermocouples();
    return input;
  }
  const auto processing = results->current_processing();
  const bool processed = processing || !results->fits().empty();
  if (!processed) not_processed_note(*results, store.dir(), input);
  reader.thermocouples();
  reader.agreements(reader.probes());
  if (processing) processing_record(*processing, input);
  const auto later = results->latest_processing();
  if (later && (!processing || later->id > processing->id) && (processed || later->status == "running")) {
    later_processing_note(*later, store.dir(), input);
  }
  try {
    input.uncertainty = stored_uncertainty(store, *results, clock);
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("The stored uncertainties could not be read: ") + e.what());
  }
  reader.maps("temperature", input.temperature_maps);
  reader.maps("displacement", input.displacement_maps);
  if (input.displacement_maps.empty() && input.thermocouples_only.empty()) {
    input.displacement_maps_note = store.frames().empty() ? "the run has no frames"
                                   : processed
                                       ? "the run was processed in probe mode (no fields): `bosfuse process RUN "
                                         "--mode full` stores them"
                                       : "the run is not processed yet: run `bosfuse process RUN`";
  }
  return input;
}

}  // namespace bosfuse::report
