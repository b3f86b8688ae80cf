#include "pipeline/process.h"

#include <fmt/format.h>
#include <glog/logging.h>

#include <chrono>
#include <cmath>
#include <future>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>

#include "acquisition/clock.h"
#include "acquisition/config/experiment_config.h"
#include "fitting/agreement.h"
#include "fitting/fit_json.h"
#include "fitting/newton_fit.h"
#include "fusion/bos_geometry.h"
#include "fusion/image_quality.h"
#include "fusion/temperature_field.h"
#include "pipeline/frame_prefetch.h"
#include "pipeline/frame_threads.h"
#include "pipeline/probe_calibration.h"
#include "pipeline/probe_fit.h"
#include "pipeline/process_frame.h"
#include "pipeline/quality_json.h"
#include "pipeline/run_selection.h"
#include "storage/processing_store.h"
#include "storage/run_lock.h"
#include "storage/run_store.h"

namespace bosfuse::pipeline {
namespace {

// For a person: a failed fit's k is "—" (the agreement's text says why), never "nan".
std::string rate_text(const fitting::NewtonFit& fit) {
  return fit.ok() && std::isfinite(fit.k_per_s.value) ? fmt::format("{:.4g} 1/s", fit.k_per_s.value) : "— (no fit)";
}

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using storage::ChannelInfo;
using storage::FrameRecord;
using Clock = std::chrono::steady_clock;

// The shared fit layout plus what was fitted and on which time base.
json fit_json(const fitting::NewtonFit& fit, const std::string& quantity, const std::string& unit,
              const storage::ExperimentClock& clock) {
  json j = fitting::to_json(fit);
  j["quantity"] = quantity;
  j["unit"] = unit;
  j["time_basis"] = clock.basis();
  return j;
}

// One frame's results into the processing's staging tables (one
// transaction), and what making them took into the processing's times.
void stage_finished(storage::ProcessingStore& results, std::int64_t processing_id, const FinishedFrame& f,
                    ProcessTimes& times) {
  times.decode_s += f.times.decode_s;
  times.evaluation_s += f.times.evaluation_s;
  times.temperature_field_s += f.times.temperature_field_s;
  times.csv_s += f.times.csv_s;
  timed(times.staging_s,
        [&] { results.stage_frame(processing_id, f.frame.id, f.summary.dump(), f.samples, f.fields); });
}

// The frame being finished on a second thread while the next one is
// evaluated (or, in turn, finished when it is staged), staged on the calling
// thread in frame order, one transaction each.
class FinishingFrame {
 public:
  FinishingFrame(storage::ProcessingStore& results, std::int64_t processing_id, ProcessTimes& times)
      : results_(results), processing_id_(processing_id), times_(times) {}

  // Stages the frame finishing before, then starts this one's finishing.
  void start(const FrameContext& ctx, const FrameRecord& frame, CheckedEvaluation evaluated, bool aside) {
    stage();
    finishing_ =
        std::async(aside ? std::launch::async : std::launch::deferred,
                   [&ctx, frame, evaluated = std::move(evaluated)] { return finish_frame(ctx, frame, evaluated); });
  }

  // The frame before one that failed is staged as in turn it would have
  // been, so a resume starts at the failing one; the first error is the one
  // to report, so this one's own is dropped.
  void stage_before_error() noexcept {
    try {
      stage();
    } catch (...) {
    }
  }

  // Waits for the frame finishing, if any, and stages it.
  void stage() {
    if (!finishing_.valid()) return;
    const FinishedFrame f = timed(times_.wait_for_finishing_s, [&] { return finishing_.get(); });
    stage_finished(results_, processing_id_, f, times_);
  }

 private:
  storage::ProcessingStore& results_;
  const std::int64_t processing_id_;
  ProcessTimes& times_;
  std::future<FinishedFrame> finishing_;  // a std::async future: its destructor waits for the thread
};

// The frames this processing refused (resumed ones included), and why.
struct RefusedFrames {
  json stored = json::array();  // [{frame_id, reason}], for the processing's summary
  std::string text;             // for a person: how many, and the first few
};

RefusedFrames refused_frames(const storage::ProcessingStore& results, std::int64_t processing_id) {
  RefusedFrames out;
  for (const auto& [frame_id, summary] : results.staged_frame_summaries(processing_id)) {
    const auto reason = refusal_of(json::parse(summary));
    if (!reason) continue;
    if (out.stored.size() < 5) out.text += fmt::format("  frame {}: {}\n", frame_id, *reason);
    out.stored.push_back({{"frame_id", frame_id}, {"reason", *reason}});
  }
  if (out.stored.empty()) return out;
  const std::size_t more = out.stored.size() > 5 ? out.stored.size() - 5 : 0;
  out.text = fmt::format("{} frames refused as not showing the reference's background; their probes have no "
                         "temperature and their fields no valid vector:\n",
                         out.stored.size()) +
             out.text + (more ? fmt::format("  ... and {} more (in the processing's summary)\n", more) : "");
  return out;
}

fitting::NewtonFit fit_at_origin(const fitting::CleanSeries& series) {
  fitting::NewtonFitOptions options;
  options.origin_s = 0.0;
  return fitting::fit_newton(series, options);
}

// What the run's experiment file says about comparing a thermocouple with
// its probe: each channel's response time constant and the margins.
struct AgreementSettings {
  std::map<std::string, double> time_constants_s;  // by acquisition::channel_name_key
  acquisition::AgreementMargins margins;
};

AgreementSettings agreement_settings(const storage::RunStore& store) {
  const std::string& text = store.run().config_toml;
  if (text.empty()) return {};
  const auto config = acquisition::parse_experiment(text, "run config");
  return {acquisition::channel_time_constants(config), config.agreement};
}

// A shift series is not a temperature: then only the two k are compared.
// A channel without a stated time constant has its lag estimated.
// The probe's systematic part, propagated through its fit, widens the
// comparison (agreement.h): what cannot be excluded is inconclusive.
fitting::Agreement agree(const fitting::NewtonFit& tc_fit, const fitting::CleanSeries& tc_series,
                         const ProbeFit& probe_fit, const ProbeSeries& probe, const std::string& name,
                         const AgreementSettings& settings) {
  fitting::AgreementOptions options;
  options.label_a = "thermocouple " + name;
  options.label_b = "BOS probe at " + name;
  options.margin_c = settings.margins.margin_c;
  options.margin_k_relative = settings.margins.margin_k_relative;
  options.b_is_temperature = probe.quantity != "shift_px";
  if (probe_fit.systematics.ok) options.b_systematic = probe_fit.systematics.combined;
  if (const auto it = settings.time_constants_s.find(acquisition::channel_name_key(name));
      it != settings.time_constants_s.end()) {
    options.a_time_constant_s = it->second;
  }
  return fitting::compare_fits(tc_fit, probe_fit.fit, tc_series,
                               options.b_is_temperature ? probe.series : fitting::CleanSeries{}, options);
}

// The processing this call carries on: a new one with resolved settings,
// or (resume) the interrupted one with its own.
struct Processing {
  std::int64_t id = 0;
  ProcessingSettings settings;
  std::string note;
};

void remove_fields_except(const fs::path& run_dir, const std::string& keep) {
  std::error_code ignored;
  const fs::path fields = run_dir / "fields";
  if (!fs::is_directory(fields)) return;
  for (const auto& entry : fs::directory_iterator(fields, ignored)) {
    if (entry.path().filename() != keep) fs::remove_all(entry.path(), ignored);
  }
}

// Why `--resume` has nothing to continue: the last processing completed,
// or failed before it staged a frame (then its error is repeated).
std::string nothing_to_resume(const fs::path& run_dir, const storage::ProcessingStore& results) {
  const auto last = results.latest_processing();
  const std::string failure = last ? processing_failure(*last) : "";
  if (failure.empty()) return "nothing to resume: the run has no interrupted processing";
  return fmt::format(
      "nothing to resume: processing {} failed before it finished a frame: {}; once that is fixed, `bosfuse process "
      "{}` starts again",
      last->id, failure, run_dir.string());
}

Processing start_processing(const fs::path& run_dir, const ProcessOptions& options, storage::ProcessingStore& results) {
  const auto unfinished = results.unfinished_processing();
  if (options.resume) {
    if (!unfinished) throw std::runtime_error(nothing_to_resume(run_dir, results));
    if (!options.overrides.empty()) {
      throw std::runtime_error(
          "--resume continues with the interrupted processing's own settings; run without "
          "--resume to process with other settings");
    }
    Processing p{unfinished->id, settings_from_json(nlohmann::json::parse(unfinished->settings_json)), ""};
    p.settings.source = fmt::format("the interrupted processing {}'s settings", unfinished->id);
    return p;
  }
  Processing p;
  if (unfinished) {
    results.abandon_processing(unfinished->id);
    std::error_code ignored;
    fs::remove_all(run_dir / "fields" / fmt::format("p{}", unfinished->id), ignored);
    p.note = fmt::format("an interrupted processing ({}) was discarded; `process --resume` continues one instead\n",
                         unfinished->id);
  }
  p.settings = resolve_settings(run_dir, options.overrides);
  p.id = results.begin_processing(to_json(p.settings).dump(), acquisition::utc_now_ns());
  return p;
}

struct FitsAndAgreements {
  std::vector<storage::FitRecord> fits;
  std::vector<storage::AgreementRecord> agreements;
  std::string text;
};

// Every fitted channel's Newton fit from the origin on (before it the
// heater may still be on), with the series it was fitted to, by channel id.
using ChannelFits = std::map<std::int64_t, std::pair<fitting::NewtonFit, fitting::CleanSeries>>;

ChannelFits fit_channels(const storage::RunStore& store, const storage::ExperimentClock& clock,
                         std::vector<storage::FitRecord>& records) {
  ChannelFits tc_fits;
  for (const auto& c : fitted_channels(store.channels())) {
    const TimeSeries tc = within(channel_series(store, c.id, clock), 0.0, INFINITY);
    auto series = fitting::clean_series(tc.t_s, tc.value, 0.0);
    auto fit = fit_at_origin(series);
    records.push_back({0, storage::FitSubject::kChannel, c.id, clock.origin_ns, fit.ok(),
                       fit_json(fit, "temperature_c", "degC", clock).dump()});
    tc_fits[c.id] = {std::move(fit), std::move(series)};
  }
  return tc_fits;
}

FitsAndAgreements fit_everything(const storage::RunStore& store, const storage::ProcessingStore& results,
                                 const FrameContext& ctx, std::int64_t processing_id,
                                 const storage::ExperimentClock& clock) {
  FitsAndAgreements out;
  const ChannelFits tc_fits = fit_channels(store, clock, out.fits);
  const auto probes = results.staged_probes(processing_id);
  const AgreementSettings agreement_options = agreement_settings(store);
  for (std::size_t p = 0; p < probes.size(); ++p) {
    const ChannelInfo& c = ctx.channels[p];
    const auto cal = ctx.calibration.find(c.id);
    const double offset_s =
        cal != ctx.calibration.end() ? cal->second.camera_offset_s : ctx.settings.geometry.camera_offset_s;
    const ProbeConversion conversion{cal == ctx.calibration.end() ? &*ctx.geometry : nullptr,
                                     ctx.settings.geometry.uncertainty, cal != ctx.calibration.end()};
    const ProbeSeries probe =
        probe_fit_series(results.staged_probe_samples(probes[p].id), clock, offset_s, conversion);
    const ProbeFit probe_fit = fit_probe(probe);
    json probe_json = fit_json(probe_fit.fit, probe.quantity, probe.quantity == "shift_px" ? "px" : "degC", clock);
    add_uncertainty_json(probe_fit, probe, probe_json);
    out.fits.push_back(
        {0, storage::FitSubject::kProbe, probes[p].id, clock.origin_ns, probe_fit.fit.ok(), probe_json.dump()});
    const auto& [tc_fit, tc_series] = tc_fits.at(c.id);
    const auto agreement = agree(tc_fit, tc_series, probe_fit, probe, c.name, agreement_options);
    json j = fitting::to_json(agreement);
    j["probe_quantity"] = probe.quantity;
    out.agreements.push_back({0, c.id, probes[p].id, j.dump()});
    out.text += fmt::format("{}: thermocouple k = {}, BOS probe ({}) k = {}\n", c.name, rate_text(tc_fit),
                            probe.quantity, rate_text(probe_fit.fit)) +
                agreement.brief_report();
  }
  return out;
}

// `last_image`: the last frame's image when this processing still has it
// (empty: read again, as after a resume that had nothing left to do).
json quality_json(const FrameContext& ctx, const RunFrames& frames, const cv::Mat& last_image,
                  const storage::ExperimentClock& clock) {
  const FrameRecord& last = frames.measurements.back();
  json j = {{"frame_id", last.id}, {"reference_frame_id", frames.reference.id}, {"t_s", clock.seconds(last.t_ns)}};
  const cv::Mat image = last_image.empty() ? load_frame(ctx.run_dir, last) : last_image;
  j.update(to_json(ctx.scene->match(image)));  // the index's keys and the verdict's
  return j;
}

// The frames a processing has still to evaluate, in time order.
std::vector<FrameRecord> frames_to_do(const RunFrames& frames, const std::set<std::int64_t>& done) {
  std::vector<FrameRecord> out;
  for (const FrameRecord& frame : frames.measurements) {
    if (!done.count(frame.id)) out.push_back(frame);
  }
  return out;
}

// The context of the process that owns the run: probes staged, the ambient
// and the calibration read from the store.
FrameContext frame_context(const fs::path& run_dir, const storage::RunStore& store, storage::ProcessingStore& results,
                           const Processing& processing, const RunFrames& frames,
                           const storage::ExperimentClock& clock) {
  FrameContext ctx;
  ctx.run_dir = run_dir;
  ctx.fields_dir = fmt::format("fields/p{}", processing.id);
  ctx.reference_frame = frames.reference;
  ctx.settings = processing.settings;
  ctx.channels = positioned_channels(store.channels());
  if (ctx.settings.probes_only && ctx.channels.empty()) {
    throw std::runtime_error(
        "no channel of the run has an image position (image_x_px, image_y_px): nothing to evaluate in probe mode");
  }
  for (const auto& c : ctx.channels) {
    ctx.points.emplace_back(*c.image_x_px, *c.image_y_px);
    ctx.probe_ids.push_back(results.stage_probe(processing.id, {0, c.id, c.name, *c.image_x_px, *c.image_y_px}));
  }
  resolve_ambient(ctx.settings.geometry, store, ctx.channels, clock, frames.reference);
  ctx.calibration = stored_calibration(results);
  load_frame_context(ctx);
  return ctx;
}

// Before the frames are shared out: the scene's search bound (search_range.h)
// found once, from the first frame to do, and stored with the processing's
// settings. Every frame's evaluator (here and in the distributor's
// processes, which get it with the plan), a resume and the next processing
// then search as far without sampling the scene again.
void settle_search_range(FrameContext& ctx, storage::ProcessingStore& results, const Processing& processing,
                         const std::vector<FrameRecord>& todo) {
  auto& x = ctx.settings.evaluator.xcorr;
  if (ctx.settings.probes_only || todo.empty() || !x.find_search_range || x.known_search ||
      ctx.settings.evaluator.method != fusion::Method::kCrossCorrelation) {
    return;
  }
  x.known_search = ctx.evaluator->search_range(load_frame(ctx.run_dir, todo.front()));
  if (!x.known_search) return;
  ProcessingSettings stored = processing.settings;  // as stored: without the ambient resolved for this run
  stored.evaluator.xcorr.known_search = x.known_search;
  results.update_running_settings(processing.id, to_json(stored).dump());
}

// The frames of a processing, evaluated and staged in frame order, one
// transaction each: here, one after the other, or by a distributor's
// processes.
struct FrameLoop {
  const FrameContext& ctx;
  storage::ProcessingStore& results;
  std::int64_t processing_id;
  ProcessTimes& times;
  std::function<void(const FrameRecord&)> staged;

  // Decoded ahead and, when asked, finished aside (ProcessOptions); returns
  // the frame `last_id`'s image when it was evaluated.
  cv::Mat here(FramePrefetch& ahead, const ProcessOptions& options, std::int64_t last_id) const {
    cv::Mat last_image;
    FinishingFrame finished_aside(results, processing_id, times);
    while (ahead.remaining() > 0 && !(options.stop && options.stop->load())) {
      try {
        PrefetchedFrame next = *ahead.next();
        times.decode_s += next.decode_seconds;
        times.wait_for_frames_s += next.wait_seconds;
        auto evaluated = timed(times.evaluation_s, [&] { return ctx.evaluate(next.image); });
        finished_aside.start(ctx, next.frame, std::move(evaluated), options.finish_aside);
        if (!options.finish_aside) finished_aside.stage();
        staged(next.frame);
        if (next.frame.id == last_id) last_image = std::move(next.image);
      } catch (...) {
        finished_aside.stage_before_error();
        throw;
      }
    }
    finished_aside.stage();
    return last_image;
  }

  // By every process of the distributor, this one included; no image is
  // kept (the frames are decoded where they are evaluated).
  cv::Mat distributed(FrameDistributor& distributor, const std::vector<FrameRecord>& todo,
                      const std::atomic<bool>* stop) const {
    distributor.run(
        plan_bytes(ctx, todo), todo.size(),
        [&](std::size_t i) { return finished_bytes(evaluate_and_finish(ctx, todo[i])); },
        [&](std::size_t, const Bytes& bytes) {
          const FinishedFrame f = finished_from_bytes(bytes);
          stage_finished(results, processing_id, f, times);
          staged(f.frame);
        },
        stop);
    return {};
  }
};

// What a processing reports before its first frame.
ProcessReport opening_report(const Processing& processing, const RunFrames& frames, const FrameContext& ctx,
                             std::size_t frames_resumed) {
  ProcessReport report;
  report.processing_id = processing.id;
  report.frames = frames.measurements.size();
  report.probes = ctx.channels.size();
  report.temperature_source = temperature_source(ctx);
  report.frames_resumed = frames_resumed;
  return report;
}

// This process's temperature solver's work (ProcessReport).
void count_solver_work(const fusion::TemperatureFieldSolver& solver, ProcessReport& report) {
  report.temperature_fields = solver.fields();
  report.temperature_analyses = solver.analyses();
  report.temperature_factorisations = solver.factorisations();
}

// What a processing whose frames are all staged is completed from.
struct StagedProcessing {
  const fs::path& run_dir;
  const storage::RunStore& store;
  storage::ProcessingStore& results;
  const FrameContext& ctx;
  const RunFrames& frames;
  const storage::ExperimentClock& clock;
  const Processing& processing;
};

// Every fit and agreement, the quality index and the summary stored, the
// staged results swapped into the current ones; `report` gets the counts.
// Returns what the refused frames and the fits say.
std::string complete_processing(const StagedProcessing& p, const cv::Mat& last_image, ProcessReport& report) {
  const auto fits_start = Clock::now();
  const FitsAndAgreements fitted = fit_everything(p.store, p.results, p.ctx, p.processing.id, p.clock);
  for (const auto& f : fitted.fits) report.fits_ok += f.ok ? 1 : 0;
  report.fits = fitted.fits.size();
  report.agreements = fitted.agreements.size();
  const auto conversions = temperature_conversions(p.results, p.ctx.channels, !p.ctx.settings.probes_only);
  const RefusedFrames refused = refused_frames(p.results, p.processing.id);
  report.frames_refused = refused.stored.size();
  const json summary = {{"frames", report.frames},
                        {"frames_refused", refused.stored},
                        {"probes", report.probes},
                        {"temperature_source", report.temperature_source},
                        {"temperature_conversions", conversions},
                        {"time_basis", p.clock.basis()},
                        {"quality", quality_json(p.ctx, p.frames, last_image, p.clock)}};
  p.results.complete_processing(p.processing.id, fitted.fits, fitted.agreements, summary.dump(),
                                acquisition::utc_now_ns());
  remove_fields_except(p.run_dir, fmt::format("p{}", p.processing.id));
  report.complete = true;
  report.times.finishing_s = std::chrono::duration<double>(Clock::now() - fits_start).count();
  return refused.text + fitted.text;
}

// The notes that open a processing's progress.
std::string opening_note(const fs::path& run_dir, const FrameContext& ctx, const storage::ExperimentClock& clock) {
  return fmt::format("processing {} ({}), settings from {}; times in {}", run_dir.string(),
                     ctx.settings.probes_only ? "probe mode" : "full fields", ctx.settings.source, clock.basis());
}

std::string geometry_note(const FrameContext& ctx) {
  return "geometry from " + ctx.settings.geometry.source + ":\n" + ctx.geometry->brief_report();
}

std::string stopped_text(std::size_t done, std::size_t frames, const fs::path& run_dir) {
  return fmt::format(
      "stopped after {} of {} frames; the run's earlier results are unchanged; `bosfuse process {} --resume` "
      "continues\n",
      done, frames, run_dir.string());
}

// The line that opens a complete processing's text.
std::string completed_text(const ProcessReport& report, const FrameContext& ctx,
                           const storage::ExperimentClock& clock) {
  return fmt::format(
      "{} frames{}, {} probes ({}), temperatures from {}; {} of {} fits ok, {} agreements, {:.1f} s; times in {}\n",
      report.frames, report.frames_resumed ? fmt::format(" ({} done before the resume)", report.frames_resumed) : "",
      report.probes, ctx.settings.probes_only ? "probe mode" : "full fields", report.temperature_source, report.fits_ok,
      report.fits, report.agreements, report.seconds, clock.basis());
}

// The frames of a run with a reference, evaluated against it, then every
// fit, agreement and the quality index; stored when every frame is done.
ProcessReport process_frames(const fs::path& run_dir, const ProcessOptions& options, const storage::RunStore& store,
                             storage::ProcessingStore& results, const storage::ExperimentClock& clock,
                             const Processing& processing, Clock::time_point start) {
  const RunFrames frames = split_frames(store.frames());
  const auto staged = results.staged_frame_ids(processing.id);
  const std::set<std::int64_t> done(staged.begin(), staged.end());
  const std::vector<FrameRecord> todo = frames_to_do(frames, done);
  // Started before the context is read, so the first frame decodes beside the reference.
  std::optional<FrameThreads> side_by_side;
  std::shared_ptr<fusion::TemperatureFieldSolver> run_solver;  // set with the context, before the threads start
  const int frames_at_once = options.frames_at_once ? options.frames_at_once : FrameThreads::default_threads();
  if (!options.distributor && frames_at_once > 1 && todo.size() > 1) {
    side_by_side.emplace(frames_at_once,
                         [&run_solver](const Bytes& plan) { return planned_frame_work_sharing(plan, run_solver); });
  }
  FrameDistributor* const distributor = options.distributor ? options.distributor
                                        : side_by_side      ? &*side_by_side
                                                            : nullptr;
  std::optional<FramePrefetch> ahead;
  if (!distributor) ahead.emplace(run_dir, todo, options.prefetch_frames);
  FrameContext ctx = frame_context(run_dir, store, results, processing, frames, clock);
  settle_search_range(ctx, results, processing, todo);
  run_solver = ctx.temperature_solver;
  // The Poisson system's analysis (~1 s at 16 MP) beside the first frames'
  // decoding and evaluation, rather than in the way of the first frame's
  // temperature field. A failure stays in the future, unread: the first
  // field's recover() meets the same problem and reports it.
  std::future<void> temperature_analysis;
  if (!ctx.settings.probes_only && !todo.empty()) {
    temperature_analysis = std::async(
        std::launch::async, [solver = ctx.temperature_solver, grid = ctx.evaluator->grid()] { solver->prepare(grid); });
  }

  ProcessReport report = opening_report(processing, frames, ctx, done.size());
  auto progress = [&](std::size_t n, const std::string& line, bool frame = false) {
    if (options.progress) options.progress({n, report.frames, line, frame});
  };
  progress(done.size(), opening_note(run_dir, ctx, clock));
  if (!ctx.settings.probes_only) progress(done.size(), geometry_note(ctx));
  std::size_t n = done.size();
  auto frame_staged = [&](const FrameRecord& frame) {
    progress(++n, fmt::format("frame {} (t = {:.2f} s) evaluated", frame.id, clock.seconds(frame.t_ns)), true);
  };
  const FrameLoop loop{ctx, results, processing.id, report.times, frame_staged};
  // The quality index's, kept rather than decoded twice.
  const cv::Mat last_image = distributor ? loop.distributed(*distributor, todo, options.stop)
                                         : loop.here(*ahead, options, frames.measurements.back().id);
  count_solver_work(*ctx.temperature_solver, report);
  if (n < report.frames) {
    report.text = processing.note + stopped_text(n, report.frames, run_dir);
    return report;
  }
  const std::string details =
      complete_processing({run_dir, store, results, ctx, frames, clock, processing}, last_image, report);
  report.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  report.text = processing.note + completed_text(report, ctx, clock) + details;
  // How the frames were shared out is about the machine, not the results: a note.
  if (distributor && options.progress) options.progress({report.frames, report.frames, distributor->brief_report(), false});
  return report;
}

// A run with nothing for BOS to evaluate (`why`): each thermocouple's
// Newton fit, as a run with frames gets it, stored as a complete processing
// with no probes, agreements or fields.
ProcessReport process_thermocouples_only(const fs::path& run_dir, const ProcessOptions& options,
                                         const storage::RunStore& store, storage::ProcessingStore& results,
                                         const storage::ExperimentClock& clock, const Processing& processing,
                                         const std::string& why, Clock::time_point start) {
  const std::string note = why + ": no BOS evaluation was done; the thermocouples are fitted";
  if (options.progress) options.progress({0, 0, note, false});
  const auto fits_start = Clock::now();
  std::vector<storage::FitRecord> fits;
  const ChannelFits tc_fits = fit_channels(store, clock, fits);
  ProcessReport report;
  report.processing_id = processing.id;
  report.temperature_source = "none";
  report.fits = fits.size();
  for (const auto& f : fits) report.fits_ok += f.ok ? 1 : 0;
  const json summary = {{"frames", 0},
                        {"probes", 0},
                        {"temperature_source", report.temperature_source},
                        {"thermocouples_only", why},
                        {"time_basis", clock.basis()}};
  results.complete_processing(processing.id, fits, {}, summary.dump(), acquisition::utc_now_ns());
  remove_fields_except(run_dir, "");
  report.complete = true;
  report.times.finishing_s = std::chrono::duration<double>(Clock::now() - fits_start).count();
  report.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::string fitted;
  for (const auto& c : fitted_channels(store.channels())) {
    const auto& fit = tc_fits.at(c.id).first;
    fitted += fit.ok() ? fmt::format("{}: thermocouple k = {:.4g} 1/s\n", c.name, fit.k_per_s.value)
                       : fmt::format("{}: thermocouple: no fit\n", c.name);
  }
  report.text = processing.note +
                fmt::format("thermocouples only ({}); {} of {} fits ok, {:.1f} s; times in {}\n", why,
                            report.fits_ok, report.fits, report.seconds, clock.basis()) +
                fitted;
  return report;
}

// A processing that failed says so in its row, never left looking
// interrupted (ProcessingStore::fail_processing). Its own failure to do so
// must not hide the error being reported.
void record_failure(storage::ProcessingStore& results, std::int64_t processing_id, const std::string& error) noexcept {
  try {
    results.fail_processing(processing_id, json{{"failure", error}}.dump(), acquisition::utc_now_ns());
  } catch (...) {
  }
}

}  // namespace

std::string processing_failure(const storage::ProcessingRecord& processing) {
  const auto summary = nlohmann::json::parse(processing.summary_json, nullptr, false);
  if (!summary.is_object() || !summary.contains("failure") || !summary.at("failure").is_string()) return "";
  return summary.at("failure").get<std::string>();
}

std::string ProcessOptions::Validate() const {
  if (frames_at_once < 0) {
    return fmt::format("frames_at_once is {}; it must be 0 (chosen for this machine), 1 or more", frames_at_once);
  }
  if (prefetch_frames < 0) {
    return fmt::format("prefetch_frames is {}; it must be 0 (decode on the calling thread) or more", prefetch_frames);
  }
  return "";
}

ProcessReport process_run(const fs::path& run_dir, const ProcessOptions& options) {
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres' own logging; the fit summaries say it better
  const auto start = Clock::now();
  if (const std::string problem = options.Validate(); !problem.empty()) {
    throw std::invalid_argument("process options: " + problem);
  }
  // Opened first: a folder without a run, or with one a newer bosfuse
  // wrote, is refused before a lock file is made in it.
  const auto store = storage::RunStore::open(run_dir);
  const auto lock = storage::RunLock::try_acquire(run_dir, "process.lock");
  if (!lock) {
    throw std::runtime_error("another bosfuse is processing " + run_dir.string() + " (" +
                             storage::RunLock::holder(run_dir, "process.lock") + ")");
  }
  storage::ProcessingStore results(run_dir, true);
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  const Processing processing = start_processing(run_dir, options, results);
  try {
    if (const std::string why = why_no_bos_evaluation(store.frames()); !why.empty()) {
      return process_thermocouples_only(run_dir, options, store, results, clock, processing, why, start);
    }
    return process_frames(run_dir, options, store, results, clock, processing, start);
  } catch (const std::exception& e) {
    record_failure(results, processing.id, e.what());
    throw;
  }
}

}  // namespace bosfuse::pipeline
