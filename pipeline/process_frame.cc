#include "pipeline/process_frame.h"

#include <fmt/format.h>

#include <cmath>

#include "fitting/fit_json.h"
#include "fusion/temperature_budget.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/field_csv.h"
#include "pipeline/run_selection.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using storage::ChannelInfo;
using storage::FrameRecord;

// The nodes of a grid around a point and their bilinear weights (those
// above rounding); empty outside the grid.
struct BilinearNodes {
  std::vector<std::size_t> nodes;
  std::vector<double> weights;
};

BilinearNodes bilinear_nodes(const fusion::DisplacementField& field, cv::Point2d p) {
  const auto& origin = field.at(0, 0);
  const double step = field.cols > 1 ? field.at(0, 1).x_px - origin.x_px : 1.0;
  const double fx = (p.x - origin.x_px) / step, fy = (p.y - origin.y_px) / step;
  if (!(fx >= 0 && fy >= 0 && fx <= field.cols - 1 && fy <= field.rows - 1)) return {};
  const int c0 = std::min(static_cast<int>(fx), std::max(field.cols - 2, 0));
  const int r0 = std::min(static_cast<int>(fy), std::max(field.rows - 2, 0));
  const double ax = fx - c0, ay = fy - r0;
  BilinearNodes out;
  for (int dr = 0; dr <= 1; ++dr) {
    for (int dc = 0; dc <= 1; ++dc) {
      const double w = (dr ? ay : 1 - ay) * (dc ? ax : 1 - ax);
      if (w <= 1e-12) continue;
      const int r = std::min(r0 + dr, field.rows - 1), c = std::min(c0 + dc, field.cols - 1);
      out.nodes.push_back(static_cast<std::size_t>(r) * field.cols + c);
      out.weights.push_back(w);
    }
  }
  return out;
}

bool has_sigma(double sigma_px) { return std::isfinite(sigma_px) && sigma_px > 0; }

// The shift at a probe and its σ (0: not estimated); valid only when every
// node it uses is.
struct PointShift {
  double u_px = 0, v_px = 0;
  bool valid = false;
  double sigma_u_px = 0, sigma_v_px = 0;
};

// The displacement grid interpolated bilinearly at a point. Its σ is the
// same weights applied to the nodes' σ: the σ of the average if the nodes'
// errors were fully correlated, an upper bound whatever they are (|ρ| ≤ 1).
// Chosen because neighbouring windows overlap (50 % at the default step),
// so their errors share pixels and are not independent, and their actual
// correlation is not known; the independent-node value, √Σ wᵢ²σᵢ², would be
// up to half this at a cell's centre and could understate it.
PointShift shift_at(const fusion::DisplacementField& field, const BilinearNodes& around) {
  if (around.nodes.empty()) return {};
  PointShift out{0, 0, true};
  bool every_sigma = true;
  for (std::size_t k = 0; k < around.nodes.size(); ++k) {
    const double w = around.weights[k];
    const auto& v = field.vectors[around.nodes[k]];
    out.u_px += w * v.u_px;
    out.v_px += w * v.v_px;
    out.valid = out.valid && v.valid();
    every_sigma = every_sigma && has_sigma(v.sigma_u_px) && has_sigma(v.sigma_v_px);
    out.sigma_u_px += w * v.sigma_u_px;
    out.sigma_v_px += w * v.sigma_v_px;
  }
  if (!every_sigma) out.sigma_u_px = out.sigma_v_px = 0;
  return out;
}

// σ of |(u, v)| to first order, u and v's errors taken as independent;
// at a zero shift (no direction) the mean of the two variances.
std::optional<double> magnitude_sigma_px(const PointShift& s) {
  if (!has_sigma(s.sigma_u_px) || !has_sigma(s.sigma_v_px)) return std::nullopt;
  const double shift = std::hypot(s.u_px, s.v_px);
  const double su2 = s.sigma_u_px * s.sigma_u_px, sv2 = s.sigma_v_px * s.sigma_v_px;
  if (!(shift > 1e-12)) return std::sqrt(0.5 * (su2 + sv2));
  return std::sqrt(s.u_px * s.u_px * su2 + s.v_px * s.v_px * sv2) / shift;
}

json evaluation_json(const fusion::EvaluationSummary& s) {
  return {{"method", s.method},
          {"vectors", s.vectors},
          {"valid", s.valid},
          {"masked", s.masked},
          {"no_texture", s.no_texture},
          {"no_peak", s.no_peak},
          {"beyond_search", s.beyond_search},
          {"outliers_replaced", s.outliers_replaced},
          {"refined_fraction", s.refined_fraction},
          {"search",
           {{"max_shift_px", s.max_shift_px},
            {"first_window_px", s.first_window_px},
            {"from_scene", s.search_from_scene},
            {"stored", s.search_stored},
            {"widened", s.search_widened},
            {"beyond_reach", s.search_beyond_reach},
            {"first_pass_windows", s.first_pass_windows},
            {"first_pass_on_bound", s.first_pass_on_bound}}},
          {"seconds", s.seconds}};
}

std::string boundary_text(const fusion::TemperatureFieldOptions& o) {
  std::string open;
  for (const auto& [flag, name] :
       {std::pair{o.open_top, "top"}, {o.open_bottom, "bottom"}, {o.open_left, "left"}, {o.open_right, "right"}}) {
    if (flag) open += std::string(open.empty() ? "" : ", ") + name;
  }
  return open.empty() ? "ambient air on the field's border" : "ambient air on the border except the open " + open;
}

// A probe's temperature by the physical model and its uncertainties.
struct ModelTemperature {
  std::optional<double> t_c, sigma_random_c, sigma_systematic_c;
  // The window-average correction included in t_c and its σ (in the systematic σ).
  std::optional<double> window_correction_c, window_correction_sigma_c;
};

// Everything measured at the probes of one frame, and the temperature field
// behind the full field's probes.
struct FrameResult {
  std::vector<PointShift> shifts;
  std::vector<ModelTemperature> model;
  std::optional<fusion::TemperatureFieldResult> temperature;
};

std::optional<double> finite_or_none(double value) {
  return std::isfinite(value) ? std::optional<double>(value) : std::nullopt;
}

// The physical model's temperature at a probe, the bilinear interpolation of
// the field's nodes corrected for the chain's averaging (the window's and
// the solve's smoothing of a curved field, fusion/temperature_budget.h),
// with the random σ of that interpolation (exact, through the solve:
// average_sigma_c) and its Type-B budget with the run's
// [geometry.uncertainty], the correction's uncertainty included. Where no
// correction can be made (a neighbour of the nearest node not measured),
// the interpolated value and no such term, as before.
ModelTemperature model_temperature(const FrameContext& ctx, const fusion::EvaluationResult& evaluated,
                                   const fusion::TemperatureField& field, cv::Point2d p, const BilinearNodes& around) {
  ModelTemperature out;
  out.t_c = field.temperature_at(p.x, p.y);
  if (!out.t_c || around.nodes.empty()) return out;
  out.sigma_random_c = ctx.temperature_solver->average_sigma_c(evaluated.field, field, around.nodes, around.weights);
  if (out.sigma_random_c) out.sigma_random_c = finite_or_none(*out.sigma_random_c);
  const auto chain = fusion::chain_curvature_coefficient(ctx.settings.evaluator, field.step_px);
  std::optional<double> correction_sigma_c;
  if (const auto correction = fusion::window_correction(field, p.x, p.y, chain)) {
    const auto noise =
        ctx.temperature_solver->average_sigma_c(evaluated.field, field, correction->nodes, correction->weights);
    out.window_correction_c = correction->correction_c;
    *out.t_c += correction->correction_c;
    correction_sigma_c = fusion::window_correction_sigma_c(*correction, noise);
    out.window_correction_sigma_c = correction_sigma_c;
  }
  const auto budget = fusion::temperature_budget(*ctx.geometry, ctx.settings.geometry.uncertainty, *out.t_c,
                                                 correction_sigma_c);
  out.sigma_systematic_c = finite_or_none(budget.combined_c);
  return out;
}

FrameResult measure_full(const FrameContext& ctx, const fusion::EvaluationResult& evaluated, ProcessTimes& times) {
  FrameResult out;
  if (evaluated.field.rows >= 3 && evaluated.field.cols >= 3) {
    out.temperature =
        timed(times.temperature_field_s, [&] { return ctx.temperature_solver->recover(evaluated.field); });
  }
  for (const auto& p : ctx.points) {
    const BilinearNodes around = bilinear_nodes(evaluated.field, p);
    out.shifts.push_back(shift_at(evaluated.field, around));
    out.model.push_back(
        out.temperature ? timed(times.temperature_field_s,
                                [&] { return model_temperature(ctx, evaluated, out.temperature->field, p, around); })
                        : ModelTemperature{});
  }
  return out;
}

FrameResult measure_probes(const fusion::EvaluationResult& evaluated) {
  FrameResult out;
  for (const auto& v : evaluated.field.vectors) {
    const bool sigma = has_sigma(v.sigma_u_px) && has_sigma(v.sigma_v_px);
    out.shifts.push_back({v.u_px, v.v_px, v.valid(), sigma ? v.sigma_u_px : 0, sigma ? v.sigma_v_px : 0});
    out.model.emplace_back();
  }
  return out;
}

// A refused frame's probes: no shift, none valid, so no temperature.
FrameResult measure_nothing(const FrameContext& ctx) {
  FrameResult out;
  out.shifts.resize(ctx.channels.size());
  out.model.resize(ctx.channels.size());
  return out;
}

FrameResult measure(const FrameContext& ctx, const CheckedEvaluation& evaluated, ProcessTimes& times) {
  if (evaluated.refused) return measure_nothing(ctx);
  return ctx.settings.probes_only ? measure_probes(evaluated) : measure_full(ctx, evaluated, times);
}

json refusal_json(const fusion::SceneMatch& scene) {
  return {{"reason", scene.Describe()},
          {"verdict", fusion::to_string(scene.verdict)},
          {"scene_correlation", scene.correlation},
          {"min_correlation", scene.options.min_correlation}};
}

// The window-average correction each probe's temperature includes, with its
// σ (in the sample's systematic σ), and the chain's coefficient behind it:
// the probe samples' table has no column for it (a schema change).
json window_correction_json(const FrameContext& ctx, const FrameResult& result) {
  const auto chain = fusion::chain_curvature_coefficient(ctx.settings.evaluator, result.temperature->field.step_px);
  json probes = json::array();
  for (std::size_t p = 0; p < ctx.channels.size() && p < result.model.size(); ++p) {
    const ModelTemperature& m = result.model[p];
    probes.push_back({{"probe", ctx.channels[p].name},
                      {"correction_c", m.window_correction_c ? fitting::number_or_null(*m.window_correction_c) : json(nullptr)},
                      {"sigma_c", m.window_correction_sigma_c ? fitting::number_or_null(*m.window_correction_sigma_c) : json(nullptr)}});
  }
  return {{"kappa_px2", chain.kappa_px2},
          {"kappa_sigma_px2", chain.sigma_px2},
          {"effective_window_px", chain.effective_window_px()},
          {"probes", probes}};
}

// The full field's files and their rows.
std::vector<storage::FieldRecord> write_fields(const FrameContext& ctx, const FrameRecord& frame,
                                               const fusion::EvaluationResult& evaluated, const FrameResult& result,
                                               const json& summary, ProcessTimes& times) {
  const std::string stem = fmt::format("{}/frame_{:06d}", ctx.fields_dir, frame.id);
  std::vector<storage::FieldRecord> fields;
  timed(times.csv_s, [&] { write_csv(evaluated.field, ctx.run_dir / (stem + "_displacement.csv")); });
  fields.push_back({0, frame.id, "displacement", stem + "_displacement.csv", summary.dump()});
  if (!result.temperature) return fields;
  timed(times.csv_s, [&] { write_csv(result.temperature->field, ctx.run_dir / (stem + "_temperature.csv")); });
  const auto& s = result.temperature->summary;
  fields.push_back({0, frame.id, "temperature", stem + "_temperature.csv",
                    json{{"min_c", fitting::number_or_null(s.min_c)},
                         {"max_c", fitting::number_or_null(s.max_c)},
                         {"unmeasured_nodes", s.unmeasured_nodes},
                         {"unphysical_nodes", s.unphysical_nodes},
                         {"boundary", boundary_text(ctx.settings.geometry.temperature_field)},
                         {"window_correction", window_correction_json(ctx, result)}}
                        .dump()});
  return fields;
}

std::optional<double> positive_or_none(double sigma) { return has_sigma(sigma) ? std::optional(sigma) : std::nullopt; }

// Each probe's sample: its shift, and its temperature by the calibration,
// else by the physical model, each with its σ. Under a calibration
// T = T_anchor + slope · shift: the random σ is |slope| · σ of the shift,
// and the systematic one combines |shift| · σ of the slope (the
// calibration's standard error) with the anchor's σ (the ambient's), both
// common to every sample of the series.
std::vector<storage::ProbeSampleRecord> samples_of(const FrameContext& ctx, const FrameRecord& frame,
                                                   const FrameResult& result) {
  std::vector<storage::ProbeSampleRecord> samples;
  for (std::size_t p = 0; p < ctx.channels.size(); ++p) {
    const PointShift& s = result.shifts[p];
    const double shift = std::hypot(s.u_px, s.v_px);
    storage::ProbeSampleRecord sample;
    sample.probe_id = ctx.probe_ids[p];
    sample.frame_id = frame.id;
    sample.t_ns = frame.t_ns;
    sample.u_px = s.u_px;
    sample.v_px = s.v_px;
    sample.shift_px = shift;
    sample.valid = s.valid;
    if (s.valid) {
      sample.sigma_u_px = positive_or_none(s.sigma_u_px);
      sample.sigma_v_px = positive_or_none(s.sigma_v_px);
      sample.sigma_shift_px = magnitude_sigma_px(s);
      const auto cal = ctx.calibration.find(ctx.channels[p].id);
      if (cal != ctx.calibration.end()) {
        sample.temperature_c = calibrated_temperature_c(ctx.calibration, ctx.channels[p].id, shift);
        if (sample.sigma_shift_px)
          sample.sigma_random_c = std::abs(cal->second.slope_c_per_px) * *sample.sigma_shift_px;
        const double systematic_c =
            std::hypot(shift * cal->second.slope_std_error_c_per_px, cal->second.anchor_std_error_c);
        if (systematic_c > 0) sample.sigma_systematic_c = systematic_c;
      } else {
        const ModelTemperature& m = result.model[p];
        sample.temperature_c = m.t_c;
        sample.sigma_random_c = m.sigma_random_c;
        sample.sigma_systematic_c = m.sigma_systematic_c;
      }
    }
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace

CheckedEvaluation FrameContext::evaluate(const cv::Mat& measurement) const {
  CheckedEvaluation out;
  if (scene) {
    auto match = scene->match(measurement);
    log_warnings(match.warnings);
    if (!match.same_scene()) out.refused = std::move(match);
  }
  static_cast<fusion::EvaluationResult&>(out) =
      settings.probes_only ? evaluator->probe(measurement, points) : evaluator->evaluate(measurement);
  log_evaluation(out.summary);
  if (out.refused) fusion::refuse_vectors(out);
  return out;
}

std::optional<std::string> refusal_of(const nlohmann::json& frame_summary) {
  const auto refused = frame_summary.find("refused");
  if (refused == frame_summary.end()) return std::nullopt;
  return refused->at("reason").get<std::string>();
}

FinishedFrame finish_frame(const FrameContext& ctx, const FrameRecord& frame, const CheckedEvaluation& evaluated) {
  FinishedFrame out{frame, evaluation_json(evaluated.summary), {}, {}, {}};
  const FrameResult result = measure(ctx, evaluated, out.times);
  if (evaluated.refused) out.summary["refused"] = refusal_json(*evaluated.refused);
  if (!ctx.settings.probes_only) out.fields = write_fields(ctx, frame, evaluated, result, out.summary, out.times);
  out.samples = samples_of(ctx, frame, result);
  return out;
}

std::string temperature_source(const FrameContext& ctx) {
  return !ctx.calibration.empty()    ? "calibration"
         : !ctx.settings.probes_only ? "physical model"
                                     : "none (probe fits on the shift; run bosfuse calibrate)";
}

std::vector<storage::ProbeSampleRecord> probe_samples(const FrameContext& ctx, const FrameRecord& frame,
                                                      const CheckedEvaluation& evaluated) {
  ProcessTimes unused;
  return samples_of(ctx, frame, measure(ctx, evaluated, unused));
}

namespace {

json frame_json(const FrameRecord& f) {
  return {{"id", f.id},
          {"t_ns", f.t_ns},
          {"path", f.path},
          {"width_px", f.width_px},
          {"height_px", f.height_px},
          {"bit_depth", f.bit_depth}};
}

FrameRecord frame_from_json(const json& j) {
  FrameRecord f;
  f.id = j.at("id").get<std::int64_t>();
  f.t_ns = j.at("t_ns").get<std::int64_t>();
  f.path = j.at("path").get<std::string>();
  f.width_px = j.at("width_px").get<int>();
  f.height_px = j.at("height_px").get<int>();
  f.bit_depth = j.at("bit_depth").get<int>();
  return f;
}

json optional_json(const std::optional<double>& value) { return value ? json(*value) : json(nullptr); }

std::optional<double> optional_from_json(const json& j) {
  return j.is_null() ? std::nullopt : std::optional<double>(j.get<double>());
}

json sample_json(const storage::ProbeSampleRecord& s) {
  return {s.probe_id,
          s.frame_id,
          s.t_ns,
          s.u_px,
          s.v_px,
          s.shift_px,
          optional_json(s.temperature_c),
          s.valid,
          optional_json(s.sigma_u_px),
          optional_json(s.sigma_v_px),
          optional_json(s.sigma_shift_px),
          optional_json(s.sigma_random_c),
          optional_json(s.sigma_systematic_c)};
}

storage::ProbeSampleRecord sample_from_json(const json& j) {
  return {j.at(0).get<std::int64_t>(), j.at(1).get<std::int64_t>(),  j.at(2).get<std::int64_t>(),
          j.at(3).get<double>(),       j.at(4).get<double>(),        j.at(5).get<double>(),
          optional_from_json(j.at(6)), j.at(7).get<bool>(),          optional_from_json(j.at(8)),
          optional_from_json(j.at(9)), optional_from_json(j.at(10)), optional_from_json(j.at(11)),
          optional_from_json(j.at(12))};
}

}  // namespace

Bytes finished_bytes(const FinishedFrame& f) {
  json samples = json::array(), fields = json::array();
  for (const auto& s : f.samples) samples.push_back(sample_json(s));
  for (const auto& r : f.fields) fields.push_back({r.frame_id, r.kind, r.path, r.json});
  const json j = {{"frame", frame_json(f.frame)},
                  {"summary", f.summary},
                  {"samples", samples},
                  {"fields", fields},
                  {"times", {f.times.decode_s, f.times.evaluation_s, f.times.temperature_field_s, f.times.csv_s}}};
  return json::to_cbor(j);
}

FinishedFrame finished_from_bytes(const Bytes& bytes) {
  const json j = json::from_cbor(bytes);
  FinishedFrame f;
  f.frame = frame_from_json(j.at("frame"));
  f.summary = j.at("summary");
  for (const auto& s : j.at("samples")) f.samples.push_back(sample_from_json(s));
  for (const auto& r : j.at("fields")) {
    f.fields.push_back({0, r.at(0).get<std::int64_t>(), r.at(1).get<std::string>(), r.at(2).get<std::string>(),
                        r.at(3).get<std::string>()});
  }
  const json& t = j.at("times");
  f.times.decode_s = t.at(0).get<double>();
  f.times.evaluation_s = t.at(1).get<double>();
  f.times.temperature_field_s = t.at(2).get<double>();
  f.times.csv_s = t.at(3).get<double>();
  return f;
}

// A frame from its file to its finished results: what every process of a
// distributed processing does with the frames it is handed.
FinishedFrame evaluate_and_finish(const FrameContext& ctx, const FrameRecord& frame) {
  ProcessTimes times;
  const cv::Mat image = timed(times.decode_s, [&] { return load_frame(ctx.run_dir, frame); });
  const auto evaluated = timed(times.evaluation_s, [&] { return ctx.evaluate(image); });
  FinishedFrame f = finish_frame(ctx, frame, evaluated);
  f.times.decode_s = times.decode_s;
  f.times.evaluation_s = times.evaluation_s;
  return f;
}

// The reference, the mask, the evaluator and the temperature solver of a
// context whose data is set: made the same way by every process.
void load_frame_context(FrameContext& ctx) {
  // Every pass run, as in the full field; with the exact context (-1) a probe
  // then equals the full field at its point.
  ctx.settings.evaluator.xcorr.convergence_px = 0;
  ctx.geometry.emplace(ctx.settings.geometry.geometry);
  ctx.reference = load_frame(ctx.run_dir, ctx.reference_frame);
  ctx.mask = load_mask(ctx.run_dir, ctx.settings.mask);
  ctx.evaluator = std::make_unique<fusion::DisplacementEvaluator>(ctx.reference, ctx.settings.evaluator, ctx.mask);
  ctx.scene = std::make_shared<const fusion::SceneMatcher>(ctx.reference);
  ctx.temperature_solver =
      std::make_shared<fusion::TemperatureFieldSolver>(*ctx.geometry, ctx.settings.geometry.temperature_field);
  // Only a processing writes fields; the live page's context has no folder for them.
  if (!ctx.settings.probes_only && !ctx.fields_dir.empty()) fs::create_directories(ctx.run_dir / ctx.fields_dir);
}

// What another process needs to evaluate and finish any of `frames` as this
// one would: the context's data (not the store: a run folder on a shared
// filesystem is read by every node, but its database is written by one).
Bytes plan_bytes(const FrameContext& ctx, const std::vector<FrameRecord>& frames) {
  json channels = json::array(), calibration = json::array(), todo = json::array();
  for (std::size_t p = 0; p < ctx.channels.size(); ++p) {
    channels.push_back({ctx.channels[p].id, ctx.channels[p].name, ctx.points[p].x, ctx.points[p].y, ctx.probe_ids[p]});
  }
  for (const auto& [channel, c] : ctx.calibration) {
    calibration.push_back({channel, c.slope_c_per_px, c.reference_temperature_c, c.camera_offset_s,
                           c.slope_std_error_c_per_px, c.anchor_std_error_c});
  }
  for (const auto& f : frames) todo.push_back(frame_json(f));
  return json::to_cbor(json{{"run_dir", fs::absolute(ctx.run_dir).string()},
                            {"fields_dir", ctx.fields_dir},
                            {"reference", frame_json(ctx.reference_frame)},
                            {"settings", to_json(ctx.settings)},
                            {"channels", channels},
                            {"calibration", calibration},
                            {"frames", todo}});
}

// The context a plan describes, loaded, and the frames to do.
std::pair<FrameContext, std::vector<FrameRecord>> context_from_plan(const Bytes& plan) {
  const json j = json::from_cbor(plan);
  FrameContext ctx;
  ctx.run_dir = j.at("run_dir").get<std::string>();
  ctx.fields_dir = j.at("fields_dir").get<std::string>();
  ctx.reference_frame = frame_from_json(j.at("reference"));
  ctx.settings = settings_from_json(j.at("settings"));
  for (const auto& c : j.at("channels")) {
    ChannelInfo info;
    info.id = c.at(0).get<std::int64_t>();
    info.name = c.at(1).get<std::string>();
    ctx.channels.push_back(info);
    ctx.points.emplace_back(c.at(2).get<double>(), c.at(3).get<double>());
    ctx.probe_ids.push_back(c.at(4).get<std::int64_t>());
  }
  for (const auto& c : j.at("calibration")) {
    ctx.calibration[c.at(0).get<std::int64_t>()] = {c.at(1).get<double>(), c.at(2).get<double>(), c.at(3).get<double>(),
                                                    c.at(4).get<double>(), c.at(5).get<double>()};
  }
  std::vector<FrameRecord> frames;
  for (const auto& f : j.at("frames")) frames.push_back(frame_from_json(f));
  load_frame_context(ctx);
  return {std::move(ctx), std::move(frames)};
}

FrameWork planned_frame_work_sharing(const Bytes& plan, std::shared_ptr<fusion::TemperatureFieldSolver> solver) {
  auto planned = std::make_shared<std::pair<FrameContext, std::vector<FrameRecord>>>(context_from_plan(plan));
  if (solver) planned->first.temperature_solver = std::move(solver);
  return
      [planned](std::size_t i) { return finished_bytes(evaluate_and_finish(planned->first, planned->second.at(i))); };
}

FrameWork planned_frame_work(const Bytes& plan) { return planned_frame_work_sharing(plan, nullptr); }

}  // namespace bosfuse::pipeline
