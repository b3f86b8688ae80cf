#include "app/run_processing.h"

#include <fmt/format.h>
#include <glog/logging.h>

#include <chrono>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "app/image_io.h"
#include "fitting/agreement.h"
#include "fitting/fit_json.h"
#include "fitting/newton_fit.h"
#include "fusion/bos_geometry.h"
#include "fusion/calibration.h"
#include "fusion/temperature_field.h"
#include "fusion/time_alignment.h"
#include "storage/processing_store.h"
#include "storage/run_paths.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using storage::ChannelInfo;
using storage::FrameRecord;

constexpr double kSecondsPerNs = 1e-9;

double seconds_between(std::int64_t from_ns, std::int64_t to_ns) {
  return static_cast<double>(to_ns - from_ns) * kSecondsPerNs;
}

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

struct RunFrames {
  FrameRecord reference;
  std::vector<FrameRecord> measurements;  // in time order
  std::int64_t origin_ns = 0;             // the first measurement: t = 0 of every fit

  std::vector<double> times_s() const {
    std::vector<double> t;
    for (const auto& f : measurements) t.push_back(seconds_between(origin_ns, f.t_ns));
    return t;
  }
};

RunFrames split_frames(const std::vector<FrameRecord>& frames) {
  RunFrames out;
  bool found = false;
  for (const auto& f : frames) {
    if (f.is_reference && !found) {
      out.reference = f;
      found = true;
    } else if (!f.is_reference) {
      out.measurements.push_back(f);
    }
  }
  if (!found) throw std::runtime_error("the run has no reference frame (a frame with is_reference = 1)");
  if (out.measurements.empty()) throw std::runtime_error("the run has no frames to evaluate besides the reference");
  out.origin_ns = out.measurements.front().t_ns;
  return out;
}

// Thermocouples (any channel) with a position in the image.
std::vector<ChannelInfo> positioned_channels(const std::vector<ChannelInfo>& channels) {
  std::vector<ChannelInfo> out;
  for (const auto& c : channels) {
    if (c.image_x_px && c.image_y_px && std::isfinite(*c.image_x_px) && std::isfinite(*c.image_y_px)) out.push_back(c);
  }
  return out;
}

// A frame the run cannot deliver (missing, unreadable, or a stored path that
// leads outside the run) stops processing, naming the frame.
cv::Mat load_frame(const fs::path& run_dir, const FrameRecord& frame) {
  const std::string role = "frame " + std::to_string(frame.id);
  try {
    return read_image(storage::resolve_in_run(run_dir, frame.path).string(), role);
  } catch (const storage::StorageError& e) {
    throw std::runtime_error(role + ": " + e.what());
  }
}

struct Series {
  std::vector<double> t_s, value;
};

Series channel_series(const storage::RunStore& store, std::int64_t channel_id, std::int64_t origin_ns) {
  Series s;
  for (const auto& sample : store.read_samples(channel_id)) {
    if (sample.status != storage::SampleStatus::kOk || !sample.value) continue;
    s.t_s.push_back(seconds_between(origin_ns, sample.t_ns));
    s.value.push_back(*sample.value);
  }
  return s;
}

Series within(const Series& s, double from_s, double to_s) {
  Series out;
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    if (s.t_s[i] >= from_s && s.t_s[i] <= to_s) {
      out.t_s.push_back(s.t_s[i]);
      out.value.push_back(s.value[i]);
    }
  }
  return out;
}

json number_or_null(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

// The shared fit layout plus what was fitted.
nlohmann::ordered_json fit_json(const fitting::NewtonFit& fit, const std::string& quantity, const std::string& unit) {
  nlohmann::ordered_json j = fitting::to_json(fit);
  j["quantity"] = quantity;
  j["unit"] = unit;
  return j;
}

// °C per px of shift for a channel, from the run's newest calibration.
struct ChannelCalibration {
  double slope_c_per_px = 0;
  double reference_temperature_c = 0;
  double camera_offset_s = 0;  // the offset the calibration was made with
};

std::map<std::int64_t, ChannelCalibration> stored_calibration(const storage::ProcessingStore& results) {
  std::map<std::int64_t, ChannelCalibration> out;
  const auto record = results.latest_calibration();
  if (!record) return out;
  const json j = json::parse(record->json);
  for (const auto& c : j.at("channels")) {
    if (!c.at("ok").get<bool>()) continue;
    out[c.at("channel_id").get<std::int64_t>()] = {c.at("slope_c_per_px").get<double>(),
                                                   c.at("reference_temperature_c").get<double>(),
                                                   c.value("camera_offset_s", 0.0)};
  }
  return out;
}

// The displacement grid interpolated bilinearly at a point; valid only when
// every node it uses is.
struct PointShift {
  double u_px = 0, v_px = 0;
  bool valid = false;
};

PointShift shift_at(const fusion::DisplacementField& field, cv::Point2d p) {
  const auto& origin = field.at(0, 0);
  const double step = field.cols > 1 ? field.at(0, 1).x_px - origin.x_px : 1.0;
  const double fx = (p.x - origin.x_px) / step, fy = (p.y - origin.y_px) / step;
  if (!(fx >= 0 && fy >= 0 && fx <= field.cols - 1 && fy <= field.rows - 1)) return {};
  const int c0 = std::min(static_cast<int>(fx), std::max(field.cols - 2, 0));
  const int r0 = std::min(static_cast<int>(fy), std::max(field.rows - 2, 0));
  const double ax = fx - c0, ay = fy - r0;
  PointShift out{0, 0, true};
  for (int dr = 0; dr <= 1; ++dr) {
    for (int dc = 0; dc <= 1; ++dc) {
      const double w = (dr ? ay : 1 - ay) * (dc ? ax : 1 - ax);
      if (w <= 1e-12) continue;
      const auto& v = field.at(std::min(r0 + dr, field.rows - 1), std::min(c0 + dc, field.cols - 1));
      out.u_px += w * v.u_px;
      out.v_px += w * v.v_px;
      out.valid = out.valid && v.valid();
    }
  }
  return out;
}

json evaluation_json(const fusion::EvaluationSummary& s) {
  return {{"method", s.method},
          {"vectors", s.vectors},
          {"valid", s.valid},
          {"masked", s.masked},
          {"no_texture", s.no_texture},
          {"no_peak", s.no_peak},
          {"outliers_replaced", s.outliers_replaced},
          {"seconds", s.seconds}};
}

// Everything measured at the probes of one frame, and the field rows.
struct FrameResult {
  std::vector<PointShift> shifts;
  std::vector<std::optional<double>> model_temperature_c;
  std::vector<storage::FieldRecord> fields;
};

std::string boundary_text(const fusion::TemperatureFieldOptions& o) {
  std::string open;
  for (const auto& [flag, name] :
       {std::pair{o.open_top, "top"}, {o.open_bottom, "bottom"}, {o.open_left, "left"}, {o.open_right, "right"}}) {
    if (flag) open += std::string(open.empty() ? "" : ", ") + name;
  }
  return open.empty() ? "ambient air on the field's border" : "ambient air on the border except the open " + open;
}

FrameResult evaluate_full(const fs::path& run_dir, const FrameRecord& frame, const cv::Mat& reference,
                          const cv::Mat& measurement, const cv::Mat& mask, const std::vector<cv::Point2d>& points,
                          const ProcessOptions& options, const fusion::BosGeometry& geometry,
                          const fusion::TemperatureFieldOptions& field_options) {
  FrameResult out;
  const auto evaluated = fusion::evaluate_displacement(reference, measurement, options.evaluator, mask);
  const std::string stem = fmt::format("fields/frame_{:06d}", frame.id);
  fusion::write_csv(evaluated.field, run_dir / (stem + "_displacement.csv"));
  out.fields.push_back(
      {0, frame.id, "displacement", stem + "_displacement.csv", evaluation_json(evaluated.summary).dump()});
  std::optional<fusion::TemperatureFieldResult> temperature;
  if (evaluated.field.rows >= 3 && evaluated.field.cols >= 3) {
    temperature = fusion::recover_temperature_field(evaluated.field, geometry, field_options);
    fusion::write_csv(temperature->field, run_dir / (stem + "_temperature.csv"));
    const auto& s = temperature->summary;
    out.fields.push_back({0, frame.id, "temperature", stem + "_temperature.csv",
                          json{{"min_c", number_or_null(s.min_c)},
                               {"max_c", number_or_null(s.max_c)},
                               {"unmeasured_nodes", s.unmeasured_nodes},
                               {"unphysical_nodes", s.unphysical_nodes},
                               {"boundary", boundary_text(field_options)}}
                              .dump()});
  }
  for (const auto& p : points) {
    out.shifts.push_back(shift_at(evaluated.field, p));
    out.model_temperature_c.push_back(temperature ? temperature->field.temperature_at(p.x, p.y) : std::nullopt);
  }
  return out;
}

FrameResult evaluate_probes(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask,
                            const std::vector<cv::Point2d>& points, const ProcessOptions& options) {
  FrameResult out;
  if (points.empty()) return out;
  const auto evaluated = fusion::probe_displacement(reference, measurement, points, options.evaluator, mask);
  for (const auto& v : evaluated.field.vectors) {
    out.shifts.push_back({v.u_px, v.v_px, v.valid()});
    out.model_temperature_c.push_back(std::nullopt);
  }
  return out;
}

// Ambient for the physical model when the geometry does not give it: the
// thermocouples at the reference frame, which was taken without the flow.
double ambient_from_thermocouples(const std::vector<Series>& series, double reference_t_s, double fallback_c) {
  double sum = 0;
  int count = 0;
  for (const auto& s : series) {
    const std::vector<double> at{reference_t_s};
    const auto aligned = fusion::align_to_frames(s.t_s, s.value, at);
    if (aligned.ok(0)) sum += aligned.value[0], ++count;
  }
  return count ? sum / count : fallback_c;
}

struct ProbeSeriesData {
  std::vector<storage::ProbeSampleRecord> samples;
  std::string quantity;  // temperature_c or shift_px
};

std::optional<double> probe_temperature_c(const std::map<std::int64_t, ChannelCalibration>& calibration,
                                          std::int64_t channel_id, double shift_px, std::optional<double> model_c) {
  const auto cal = calibration.find(channel_id);
  if (cal == calibration.end()) return model_c;
  return cal->second.reference_temperature_c + cal->second.slope_c_per_px * shift_px;
}

// What every frame's evaluation needs besides the frame itself.
struct FrameContext {
  const fs::path& run_dir;
  const std::vector<ChannelInfo>& channels;
  const std::vector<cv::Point2d>& points;
  const cv::Mat& reference;
  const cv::Mat& mask;
  const fusion::BosGeometry& geometry;
  const fusion::TemperatureFieldOptions& field_options;
  const std::map<std::int64_t, ChannelCalibration>& calibration;
};

struct EvaluatedFrames {
  std::vector<ProbeSeriesData> probes;  // one per channel, samples in frame order
  std::vector<storage::FieldRecord> fields;
};

EvaluatedFrames evaluate_frames(const FrameContext& ctx, const RunFrames& frames, const ProcessOptions& options) {
  EvaluatedFrames out;
  out.probes.resize(ctx.channels.size());
  for (std::size_t i = 0; i < frames.measurements.size(); ++i) {
    const FrameRecord& frame = frames.measurements[i];
    const cv::Mat measurement = load_frame(ctx.run_dir, frame);
    const FrameResult r = options.probes_only
                              ? evaluate_probes(ctx.reference, measurement, ctx.mask, ctx.points, options)
                              : evaluate_full(ctx.run_dir, frame, ctx.reference, measurement, ctx.mask, ctx.points,
                                              options, ctx.geometry, ctx.field_options);
    out.fields.insert(out.fields.end(), r.fields.begin(), r.fields.end());
    for (std::size_t p = 0; p < ctx.channels.size(); ++p) {
      const PointShift& s = r.shifts[p];
      const double shift = std::hypot(s.u_px, s.v_px);
      const auto t_c = probe_temperature_c(ctx.calibration, ctx.channels[p].id, shift, r.model_temperature_c[p]);
      out.probes[p].samples.push_back(
          {0, frame.id, frame.t_ns, s.u_px, s.v_px, shift, s.valid ? t_c : std::nullopt, s.valid});
    }
    if (options.progress) {
      options.progress(fmt::format("frame {}/{} (id {}, t = {:.2f} s) evaluated", i + 1, frames.measurements.size(),
                                   frame.id, seconds_between(frames.origin_ns, frame.t_ns)));
    }
  }
  return out;
}

// The probe series a Newton fit sees: temperatures when every valid sample
// has one, else the shift; times on the host clock (frame time + offset).
fitting::CleanSeries probe_fit_series(ProbeSeriesData& probe, std::int64_t origin_ns, double offset_s) {
  bool all_have_temperature = true;
  for (const auto& s : probe.samples) {
    if (s.valid) all_have_temperature = all_have_temperature && s.temperature_c.has_value();
  }
  probe.quantity = all_have_temperature ? "temperature_c" : "shift_px";
  std::vector<double> t, y;
  for (const auto& s : probe.samples) {
    if (!s.valid) continue;
    t.push_back(seconds_between(origin_ns, s.t_ns) + offset_s);
    y.push_back(all_have_temperature ? *s.temperature_c : s.shift_px);
  }
  return fitting::clean_series(t, y, 0.0);
}

struct FittedPair {
  std::size_t channel_index = 0;
  fitting::NewtonFit tc_fit, probe_fit;
  fitting::CleanSeries tc_series, probe_series;
};

// A shift series is not a temperature: then only the two k are compared.
fitting::Agreement agree(const FittedPair& pair, const std::string& name, const std::string& quantity) {
  fitting::AgreementOptions options;
  options.label_a = "thermocouple " + name;
  options.label_b = "BOS probe at " + name;
  return fitting::compare_fits(pair.tc_fit, pair.probe_fit, pair.tc_series,
                               quantity == "shift_px" ? fitting::CleanSeries{} : pair.probe_series, options);
}

}  // namespace

ProcessReport process_run(const fs::path& run_dir, const ProcessOptions& options_in) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres' own logging; the fit summaries say it better
  const auto start = std::chrono::steady_clock::now();
  ProcessOptions options = options_in;
  // Every pass run, as in the full field; with the exact context (-1) a probe
  // then equals the full field at its point.
  options.evaluator.xcorr.convergence_px = 0;
  if (const auto problem = options.evaluator.Validate(); !problem.empty()) throw std::runtime_error(problem);

  storage::ProcessingStore results(run_dir, true);
  const auto store = storage::RunStore::open(run_dir);
  const RunFrames frames = split_frames(store.frames());
  const auto channels = positioned_channels(store.channels());
  if (options.probes_only && channels.empty()) {
    throw std::runtime_error(
        "no channel of the run has an image position (image_x_px, image_y_px): nothing to "
        "evaluate in probe mode");
  }
  std::vector<cv::Point2d> points;
  for (const auto& c : channels) points.emplace_back(*c.image_x_px, *c.image_y_px);
  std::vector<Series> tc_series;
  for (const auto& c : channels) tc_series.push_back(channel_series(store, c.id, frames.origin_ns));

  GeometryConfig config = resolve_geometry_config(options.geometry_file, store.run().config_toml);
  const double reference_t_s = seconds_between(frames.origin_ns, frames.reference.t_ns);
  if (!config.ambient_given) {
    config.geometry.ambient_temperature_c = ambient_from_thermocouples(
        tc_series, reference_t_s + config.camera_offset_s, config.geometry.ambient_temperature_c);
  }
  const fusion::BosGeometry geometry(config.geometry);
  const auto calibration = stored_calibration(results);

  ProcessReport report;
  report.frames = frames.measurements.size();
  report.probes = channels.size();
  if (!options.probes_only) {
    fs::create_directories(run_dir / "fields");
    if (options.progress) options.progress("geometry from " + config.source + ":\n" + geometry.brief_report());
  }
  const cv::Mat reference = load_frame(run_dir, frames.reference);
  cv::Mat mask;
  if (!options.mask_file.empty()) {
    const fs::path path =
        fs::path(options.mask_file).is_absolute() ? fs::path(options.mask_file) : run_dir / options.mask_file;
    mask = read_image(path.string(), "mask");
  }
  EvaluatedFrames evaluated = evaluate_frames(
      {run_dir, channels, points, reference, mask, geometry, config.temperature_field, calibration}, frames, options);
  auto& probe_data = evaluated.probes;
  report.temperature_source = !calibration.empty()   ? "calibration"
                              : !options.probes_only ? "physical model"
                                                     : "none (probe fits on the shift; run bosfuse calibrate)";

  // Fits over the frames' span, t = 0 at the first evaluated frame.
  const double span_end_s = seconds_between(frames.origin_ns, frames.measurements.back().t_ns);
  std::vector<storage::FitRecord> fit_rows;
  std::vector<storage::AgreementRecord> agreement_rows;
  std::string text;
  auto record_fit = [&](const fitting::NewtonFit& fit, storage::FitSubject subject, std::int64_t id,
                        const std::string& quantity, const std::string& unit) {
    fit_rows.push_back({0, subject, id, frames.origin_ns, fit.ok(), fit_json(fit, quantity, unit).dump()});
    ++report.fits;
    report.fits_ok += fit.ok() ? 1 : 0;
  };
  std::vector<FittedPair> pairs;
  for (std::size_t p = 0; p < channels.size(); ++p) {
    const Series tc = within(tc_series[p], 0.0, span_end_s);
    FittedPair pair{p, {}, {}, fitting::clean_series(tc.t_s, tc.value, 0.0), {}};
    pair.tc_fit = fitting::fit_newton(pair.tc_series);
    record_fit(pair.tc_fit, storage::FitSubject::kChannel, channels[p].id, "temperature_c", "degC");
    const auto cal = calibration.find(channels[p].id);
    const double offset_s = cal != calibration.end() ? cal->second.camera_offset_s : config.camera_offset_s;
    pair.probe_series = probe_fit_series(probe_data[p], frames.origin_ns, offset_s);
    pair.probe_fit = fitting::fit_newton(pair.probe_series);
    text += fmt::format("{}: thermocouple k = {:.4g} 1/s, BOS probe ({}) k = {:.4g} 1/s\n", channels[p].name,
                        pair.tc_fit.k_per_s.value, probe_data[p].quantity, pair.probe_fit.k_per_s.value);
    pairs.push_back(std::move(pair));
  }

  results.in_transaction([&] {
    results.clear_results();
    for (auto& pair : pairs) {
      const ChannelInfo& c = channels[pair.channel_index];
      const auto probe_id = results.add_probe({0, c.id, c.name, *c.image_x_px, *c.image_y_px});
      auto& samples = probe_data[pair.channel_index].samples;
      for (auto& s : samples) s.probe_id = probe_id;
      results.write_probe_samples(samples);
      const std::string& quantity = probe_data[pair.channel_index].quantity;
      record_fit(pair.probe_fit, storage::FitSubject::kProbe, probe_id, quantity,
                 quantity == "shift_px" ? "px" : "degC");
      const auto agreement = agree(pair, c.name, quantity);
      nlohmann::ordered_json j = fitting::to_json(agreement);
      j["probe_quantity"] = quantity;
      agreement_rows.push_back({0, c.id, probe_id, j.dump()});
      text += agreement.brief_report();
    }
    // Channel fits were counted when made; their rows are written here.
    for (const auto& f : fit_rows) results.add_fit(f);
    for (const auto& a : agreement_rows) results.add_agreement(a);
    for (const auto& f : evaluated.fields) results.add_field(f);
  });
  report.agreements = agreement_rows.size();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.text = fmt::format(
                    "{} frames, {} probes ({}), temperatures from {}; {} of {} fits ok, {} agreements, "
                    "{:.1f} s\n",
                    report.frames, report.probes, options.probes_only ? "probe mode" : "full fields",
                    report.temperature_source, report.fits_ok, report.fits, report.agreements, report.seconds) +
                text;
  return report;
}

namespace {

// The probe's valid samples on the fits' time axis (frame clock) and their shift.
struct ProbeShifts {
  std::vector<double> frame_t_s, shift_px;
};

ProbeShifts valid_shifts(const std::vector<storage::ProbeSampleRecord>& samples, std::int64_t origin_ns) {
  ProbeShifts out;
  for (const auto& s : samples) {
    if (!s.valid) continue;
    out.frame_t_s.push_back(seconds_between(origin_ns, s.t_ns));
    out.shift_px.push_back(s.shift_px);
  }
  return out;
}

// The configured offset, or the estimate when asked for and identifiable.
double camera_offset_for(const Series& tc, const ProbeShifts& probe, double configured_s, double search_s, json& record,
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
bool calibrate_channel(const Series& tc, const ProbeShifts& probe, double reference_t_s, double offset_s, json& record,
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
  const RunFrames frames = split_frames(store.frames());
  const GeometryConfig config = resolve_geometry_config(options.geometry_file, store.run().config_toml);
  const double configured_offset_s = options.camera_offset_s.value_or(config.camera_offset_s);
  const double reference_t_s = seconds_between(frames.origin_ns, frames.reference.t_ns);
  json channels = json::array();
  std::string text;
  std::size_t calibrated = 0;
  for (const auto& probe : probes) {
    if (!probe.channel_id) continue;
    json record = {{"channel_id", *probe.channel_id}, {"probe_id", probe.id}, {"name", probe.name}};
    const Series tc = channel_series(store, *probe.channel_id, frames.origin_ns);
    const ProbeShifts shifts = valid_shifts(results.probe_samples(probe.id), frames.origin_ns);
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
  results.add_calibration({0, now_ns(), j.dump()});
  return text + fmt::format("stored a calibration for {} thermocouple(s); `bosfuse process` now uses it\n", calibrated);
}

}  // namespace bosfuse::app
