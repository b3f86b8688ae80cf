#include "report/run_input.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "acquisition/image_file.h"
#include "fitting/fit_json.h"
#include "fusion/image_quality.h"
#include "report/field_csv.h"
#include "storage/processing_store.h"
#include "storage/run_paths.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

std::optional<std::int64_t> first_sample_ns(const storage::RunStore& store) {
  std::optional<std::int64_t> first;
  for (const auto& summary : store.channel_summaries()) {
    if (summary.first_ns && (!first || *summary.first_ns < *first)) first = summary.first_ns;
  }
  return first;
}

double seconds_since(std::int64_t t_ns, std::int64_t origin_ns) { return static_cast<double>(t_ns - origin_ns) * 1e-9; }

cv::Mat read_frame(const storage::RunStore& store, const storage::FrameRecord& frame) {
  fs::path path;
  try {
    path = storage::resolve_in_run(store.dir(), frame.path);
  } catch (const storage::StorageError& e) {
    throw std::runtime_error("cannot read frame " + std::to_string(frame.id) + ": " + e.what());
  }
  if (!fs::is_regular_file(path)) {
    throw std::runtime_error("cannot read frame " + std::to_string(frame.id) + " ('" + path.string() +
                             "'): no such file");
  }
  cv::Mat image = acquisition::read_image_file(path);
  if (image.empty())
    throw std::runtime_error("cannot read frame " + std::to_string(frame.id) + " ('" + path.string() + "')");
  return image;
}

using json = nlohmann::json;

// A fit stored by `bosfuse process`, its origin moved to the report's time
// base. No residuals are stored.
fitting::NewtonFit stored_fit(const storage::FitRecord& record, std::int64_t origin_ns) {
  fitting::NewtonFit fit = fitting::fit_from_json(json::parse(record.json));
  fit.origin_s = seconds_since(record.origin_t_ns, origin_ns);
  return fit;
}

// A stored field (report/field_csv.h) as a map on its grid: `value` at the
// nodes where `shown` is non-zero and finite, masked elsewhere.
MapField map_from_stored(const StoredFieldGrid& grid, const cv::Mat& value, const cv::Mat& shown) {
  MapField map;
  map.values = cv::Mat::zeros(grid.rows(), grid.cols(), CV_64F);
  map.mask = cv::Mat(grid.rows(), grid.cols(), CV_8U, cv::Scalar(255));
  map.x0_px = grid.x_px.front();
  map.y0_px = grid.y_px.front();
  map.step_px = grid.cols() > 1 ? grid.x_px[1] - grid.x_px[0] : (grid.rows() > 1 ? grid.y_px[1] - grid.y_px[0] : 1.0);
  for (int r = 0; r < grid.rows(); ++r) {
    for (int c = 0; c < grid.cols(); ++c) {
      const double v = value.at<double>(r, c);
      const double s = shown.at<double>(r, c);
      const bool is_shown = grid.present.at<std::uint8_t>(r, c) && std::isfinite(v) && std::isfinite(s) && s != 0;
      map.values.at<double>(r, c) = is_shown ? v : 0.0;
      map.mask.at<std::uint8_t>(r, c) = is_shown ? 0 : 255;
    }
  }
  return map;
}

MapField read_temperature_csv(const fs::path& path) {
  const auto grid = read_stored_field(path, kTemperatureColumns);
  const cv::Mat& t = grid.column("temperature_c");
  // Unmeasured nodes that the field filled in are shown; only missing temperatures are masked.
  MapField map = map_from_stored(grid, t, cv::Mat(t.size(), CV_64F, cv::Scalar(1)));
  map.quantity = "temperature";
  map.unit = "°C";
  return map;
}

MapField read_displacement_csv(const fs::path& path) {
  const auto grid = read_stored_field(path, kDisplacementColumns);
  cv::Mat magnitude;
  cv::magnitude(grid.column("u"), grid.column("v"), magnitude);
  MapField map = map_from_stored(grid, magnitude, grid.column("valid"));
  map.quantity = "|displacement|";
  map.unit = "px";
  return map;
}

// What `bosfuse process` stored, for the report.
struct StoredResults {
  bool probes = false;
  bool temperature_maps = false;
  bool displacement_maps = false;
};

// Adds the stored probe series (with their fits), agreements and, at the
// requested times, the stored field files as maps.
StoredResults load_stored_results(const storage::RunStore& store, std::int64_t origin_ns,
                                  const std::vector<storage::FrameRecord>& frames, const RunReportOptions& options,
                                  ReportInput& input) {
  StoredResults loaded;
  std::optional<storage::ProcessingStore> results;
  try {
    results.emplace(store.dir());
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("Stored processing results could not be read: ") + e.what());
    return loaded;
  }
  std::map<std::int64_t, std::string> channel_names;
  for (const auto& c : store.channels()) channel_names[c.id] = c.name;
  std::map<std::int64_t, storage::FitRecord> probe_fits;
  for (const auto& f : results->fits()) {
    if (f.subject == storage::FitSubject::kProbe) probe_fits[f.subject_id] = f;
  }
  std::map<std::int64_t, std::string> probe_names;
  bool any_shift = false;
  for (const auto& probe : results->probes()) {
    CurveSeries s;
    s.name = probe.name + " (BOS)";
    probe_names[probe.id] = s.name;
    s.kind = SeriesKind::kBosProbe;
    s.image_px = cv::Point2d(probe.x_px, probe.y_px);
    const auto samples = results->probe_samples(probe.id);
    const bool has_temperature =
        std::any_of(samples.begin(), samples.end(), [](const auto& p) { return p.valid && p.temperature_c; });
    any_shift = any_shift || !has_temperature;
    for (const auto& p : samples) {
      const std::optional<double> value = has_temperature ? p.temperature_c : std::optional<double>(p.shift_px);
      if (!p.valid || !value || !std::isfinite(*value)) {
        ++s.excluded_samples;
        continue;
      }
      s.time_s.push_back(seconds_since(p.t_ns, origin_ns));
      s.temperature_c.push_back(*value);
    }
    if (const auto f = probe_fits.find(probe.id); f != probe_fits.end()) {
      try {
        s.fit = stored_fit(f->second, origin_ns);
      } catch (const std::exception& e) {
        input.notes.push_back(
            fmt::format("The stored fit of probe {} could not be read ({}); it is refitted.", probe.name, e.what()));
      }
    }
    input.series.push_back(std::move(s));
    loaded.probes = true;
  }
  if (any_shift) {
    input.notes.push_back(
        "Some BOS probes have no temperature (no calibration): their series are the shift magnitude in px, not °C "
        "(run bosfuse calibrate, then bosfuse process).");
  }
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

  // Field files at the requested times: the nearest frame that has one.
  std::map<std::int64_t, storage::FrameRecord> frame_by_id;
  for (const auto& f : frames) frame_by_id[f.id] = f;
  cv::Size image_size;
  if (!frames.empty()) image_size = cv::Size(frames.front().width_px, frames.front().height_px);
  const auto fields = results->fields();
  auto add_maps = [&](const std::string& kind, std::vector<MapField>& maps) {
    std::vector<std::pair<storage::FieldRecord, std::int64_t>> candidates;  // field, frame time
    for (const auto& f : fields) {
      const auto frame = frame_by_id.find(f.frame_id);
      if (f.kind == kind && frame != frame_by_id.end()) candidates.emplace_back(f, frame->second.t_ns);
    }
    if (candidates.empty()) return false;
    std::set<std::int64_t> done;
    for (double t : options.map_times_s) {
      const auto nearest = std::min_element(candidates.begin(), candidates.end(), [&](const auto& a, const auto& b) {
        return std::abs(seconds_since(a.second, origin_ns) - t) < std::abs(seconds_since(b.second, origin_ns) - t);
      });
      if (!done.insert(nearest->first.frame_id).second) continue;
      const double frame_t = seconds_since(nearest->second, origin_ns);
      try {
        const fs::path path = storage::resolve_in_run(store.dir(), nearest->first.path);
        MapField map = kind == "temperature" ? read_temperature_csv(path) : read_displacement_csv(path);
        map.time_s = frame_t;
        map.image_size_px = image_size;
        map.source = fmt::format("stored {} field of frame {} ({}), nearest to the requested t = {:g} s", kind,
                                 nearest->first.frame_id, nearest->first.path, t);
        maps.push_back(std::move(map));
      } catch (const std::exception& e) {
        input.notes.push_back(fmt::format("No stored {} map at t = {:.1f} s: {}", kind, frame_t, e.what()));
      }
    }
    return !maps.empty();
  };
  loaded.temperature_maps = add_maps("temperature", input.temperature_maps);
  loaded.displacement_maps = add_maps("displacement", input.displacement_maps);
  return loaded;
}

}  // namespace

std::string iso8601_utc(std::int64_t t_ns) {
  std::int64_t seconds = t_ns / 1'000'000'000;
  std::int64_t rest = t_ns % 1'000'000'000;
  if (rest < 0) {
    rest += 1'000'000'000;
    --seconds;
  }
  const std::time_t t = static_cast<std::time_t>(seconds);
  std::tm fields{};
  gmtime_r(&t, &fields);
  return fmt::format("{:04d}-{:02d}-{:02d}T{:02d}:{:02d}:{:02d}.{:03d}Z", fields.tm_year + 1900, fields.tm_mon + 1,
                     fields.tm_mday, fields.tm_hour, fields.tm_min, fields.tm_sec, rest / 1'000'000);
}

MapField displacement_magnitude_map(const fusion::DisplacementField& field, cv::Size image_size_px) {
  if (field.rows <= 0 || field.cols <= 0 || field.size() != static_cast<std::size_t>(field.rows) * field.cols) {
    throw std::invalid_argument("the displacement field has no grid to map");
  }
  MapField map;
  map.quantity = "|displacement|";
  map.unit = "px";
  map.values = cv::Mat(field.rows, field.cols, CV_64F);
  map.mask = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& v = field.at(r, c);
      const bool shown = v.valid() || v.flag == fusion::VectorFlag::kOutlierReplaced;
      map.values.at<double>(r, c) = shown ? std::hypot(v.u_px, v.v_px) : 0.0;
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
  input.started_utc = iso8601_utc(run.started_ns);
  input.status = std::string(storage::to_string(run.status));
  input.px_per_mm = options.px_per_mm;

  const auto frames = store.frames();
  std::int64_t origin_ns = run.started_ns;
  if (const auto first = first_sample_ns(store)) {
    origin_ns = *first;
  } else if (!frames.empty()) {
    origin_ns = frames.front().t_ns;
  }

  auto progress = [&](const std::string& line) {
    if (options.on_progress) options.on_progress(line);
  };
  // Thermocouples.
  for (const auto& channel : store.channels()) {
    if (channel.kind != "thermocouple") continue;
    CurveSeries s;
    s.name = channel.name;
    s.kind = SeriesKind::kThermocouple;
    if (channel.image_x_px && channel.image_y_px) s.image_px = cv::Point2d(*channel.image_x_px, *channel.image_y_px);
    for (const auto& sample : store.read_samples(channel.id)) {
      if (sample.status != storage::SampleStatus::kOk || !sample.value) {
        ++s.excluded_samples;
        continue;
      }
      s.time_s.push_back(seconds_since(sample.t_ns, origin_ns));
      s.temperature_c.push_back(*sample.value);
    }
    input.series.push_back(std::move(s));
  }
  if (input.series.empty()) input.notes.push_back("The run has no thermocouple channels.");
  const StoredResults stored = load_stored_results(store, origin_ns, frames, options, input);
  progress(fmt::format("fitting {} series", input.series.size()));
  fit_missing(input, options.fit);

  // Frames: reference, measurements nearest the chosen times, quality of the last one.
  if (frames.empty()) {
    input.displacement_maps_note = "the run has no frames";
    return input;
  }
  auto reference_it = std::find_if(frames.begin(), frames.end(), [](const auto& f) { return f.is_reference; });
  if (reference_it == frames.end()) {
    reference_it = frames.begin();
    input.notes.push_back(
        fmt::format("No frame is marked as the reference; the first frame ({}) is used.", reference_it->path));
  }
  const storage::FrameRecord reference = *reference_it;
  std::vector<storage::FrameRecord> measurements;
  for (const auto& f : frames) {
    if (f.id != reference.id) measurements.push_back(f);
  }
  if (measurements.empty()) {
    input.displacement_maps_note = "the run has a reference frame but no measurement frame";
    return input;
  }
  cv::Mat reference_image;
  try {
    reference_image = read_frame(store, reference);
  } catch (const std::exception& e) {
    input.displacement_maps_note = e.what();
    return input;
  }

  if (!options.mask.empty() && options.mask.size() != reference_image.size()) {
    input.displacement_maps_note = fmt::format("the mask is {}×{} px but the frames are {}×{} px", options.mask.cols,
                                               options.mask.rows, reference_image.cols, reference_image.rows);
    return input;
  }
  std::set<std::int64_t> done;
  for (double t : stored.displacement_maps ? std::vector<double>{} : options.map_times_s) {
    const auto nearest = std::min_element(measurements.begin(), measurements.end(), [&](const auto& a, const auto& b) {
      return std::abs(seconds_since(a.t_ns, origin_ns) - t) < std::abs(seconds_since(b.t_ns, origin_ns) - t);
    });
    if (!done.insert(nearest->id).second) continue;  // two times chose the same frame
    const double frame_t = seconds_since(nearest->t_ns, origin_ns);
    progress(fmt::format("evaluating frame {} (t = {:.1f} s) against reference frame {}", nearest->id, frame_t,
                         reference.id));
    try {
      const cv::Mat image = read_frame(store, *nearest);
      const auto result = fusion::evaluate_displacement(reference_image, image, options.evaluator, options.mask);
      MapField map = displacement_magnitude_map(result.field, reference_image.size());
      map.time_s = frame_t;
      map.source = fmt::format("frame {} ({}) against reference frame {}, nearest to the requested t = {:g} s; {}",
                               nearest->id, nearest->path, reference.id, t, result.summary.BriefReport());
      input.displacement_maps.push_back(std::move(map));
    } catch (const std::exception& e) {
      input.notes.push_back(fmt::format("No displacement map at t = {:.1f} s: {}", frame_t, e.what()));
    }
  }
  if (input.displacement_maps.empty() && input.displacement_maps_note.empty()) {
    input.displacement_maps_note = "no map time was requested, or every evaluation failed (see the notes above)";
  }

  const auto& last = *std::max_element(measurements.begin(), measurements.end(),
                                       [](const auto& a, const auto& b) { return a.t_ns < b.t_ns; });
  try {
    QualityInfo quality;
    quality.index = fusion::modified_quality_index(read_frame(store, last), reference_image);
    quality.compared = fmt::format("Last frame {} (t = {:.1f} s) against reference frame {}", last.id,
                                   seconds_since(last.t_ns, origin_ns), reference.id);
    input.quality = quality;
  } catch (const std::exception& e) {
    input.notes.push_back(std::string("No image quality index: ") + e.what());
  }
  return input;
}

}  // namespace bosfuse::report
