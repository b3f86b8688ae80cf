#include "pipeline/process_frame.h"

#include <fmt/format.h>

#include <cmath>

#include "fitting/fit_json.h"
#include "pipeline/run_selection.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using storage::ChannelInfo;
using storage::FrameRecord;

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
          {"refined_fraction", s.refined_fraction},
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

// Everything measured at the probes of one frame, and the field rows.
struct FrameResult {
  std::vector<PointShift> shifts;
  std::vector<std::optional<double>> model_temperature_c;
  std::vector<storage::FieldRecord> fields;
  json summary;
};

FrameResult finish_full(const FrameContext& ctx, const FrameRecord& frame, const fusion::EvaluationResult& evaluated,
                        ProcessTimes& times) {
  FrameResult out;
  out.summary = evaluation_json(evaluated.summary);
  const std::string stem = fmt::format("{}/frame_{:06d}", ctx.fields_dir, frame.id);
  timed(times.csv_s, [&] { fusion::write_csv(evaluated.field, ctx.run_dir / (stem + "_displacement.csv")); });
  out.fields.push_back({0, frame.id, "displacement", stem + "_displacement.csv", out.summary.dump()});
  std::optional<fusion::TemperatureFieldResult> temperature;
  if (evaluated.field.rows >= 3 && evaluated.field.cols >= 3) {
    const auto& field_options = ctx.settings.geometry.temperature_field;
    temperature = timed(times.temperature_field_s, [&] { return ctx.temperature_solver->recover(evaluated.field); });
    timed(times.csv_s, [&] { fusion::write_csv(temperature->field, ctx.run_dir / (stem + "_temperature.csv")); });
    const auto& s = temperature->summary;
    out.fields.push_back({0, frame.id, "temperature", stem + "_temperature.csv",
                          json{{"min_c", fitting::number_or_null(s.min_c)},
                               {"max_c", fitting::number_or_null(s.max_c)},
                               {"unmeasured_nodes", s.unmeasured_nodes},
                               {"unphysical_nodes", s.unphysical_nodes},
                               {"boundary", boundary_text(field_options)}}
                              .dump()});
  }
  for (const auto& p : ctx.points) {
    out.shifts.push_back(shift_at(evaluated.field, p));
    out.model_temperature_c.push_back(temperature ? temperature->field.temperature_at(p.x, p.y) : std::nullopt);
  }
  return out;
}

FrameResult finish_probes(const fusion::EvaluationResult& evaluated) {
  FrameResult out;
  out.summary = evaluation_json(evaluated.summary);
  for (const auto& v : evaluated.field.vectors) {
    out.shifts.push_back({v.u_px, v.v_px, v.valid()});
    out.model_temperature_c.push_back(std::nullopt);
  }
  return out;
}

}  // namespace

FinishedFrame finish_frame(const FrameContext& ctx, const FrameRecord& frame,
                           const fusion::EvaluationResult& evaluated) {
  FinishedFrame out{frame, {}, {}, {}, {}};
  const FrameResult result =
      ctx.settings.probes_only ? finish_probes(evaluated) : finish_full(ctx, frame, evaluated, out.times);
  out.summary = result.summary;
  out.fields = result.fields;
  for (std::size_t p = 0; p < ctx.channels.size(); ++p) {
    const PointShift& s = result.shifts[p];
    const double shift = std::hypot(s.u_px, s.v_px);
    auto t_c = calibrated_temperature_c(ctx.calibration, ctx.channels[p].id, shift);
    if (!t_c) t_c = result.model_temperature_c[p];
    out.samples.push_back(
        {ctx.probe_ids[p], frame.id, frame.t_ns, s.u_px, s.v_px, shift, s.valid ? t_c : std::nullopt, s.valid});
  }
  return out;
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

json sample_json(const storage::ProbeSampleRecord& s) {
  return {s.probe_id,
          s.frame_id,
          s.t_ns,
          s.u_px,
          s.v_px,
          s.shift_px,
          s.temperature_c ? json(*s.temperature_c) : json(nullptr),
          s.valid};
}

storage::ProbeSampleRecord sample_from_json(const json& j) {
  const json& t = j.at(6);
  return {j.at(0).get<std::int64_t>(),
          j.at(1).get<std::int64_t>(),
          j.at(2).get<std::int64_t>(),
          j.at(3).get<double>(),
          j.at(4).get<double>(),
          j.at(5).get<double>(),
          t.is_null() ? std::nullopt : std::optional<double>(t.get<double>()),
          j.at(7).get<bool>()};
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
  ctx.temperature_solver =
      std::make_shared<fusion::TemperatureFieldSolver>(*ctx.geometry, ctx.settings.geometry.temperature_field);
  if (!ctx.settings.probes_only) fs::create_directories(ctx.run_dir / ctx.fields_dir);
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
    calibration.push_back({channel, c.slope_c_per_px, c.reference_temperature_c, c.camera_offset_s});
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
    ctx.calibration[c.at(0).get<std::int64_t>()] = {c.at(1).get<double>(), c.at(2).get<double>(),
                                                    c.at(3).get<double>()};
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
