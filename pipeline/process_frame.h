#pragma once
// One frame's work in a processing (process.h): the context every process
// of a processing holds — the settings, probes, calibration, reference and
// its prepared evaluator and temperature solver — and a frame from its file
// to the results one transaction stages. The context's data and a frame's
// results also travel as bytes: CBOR, binary, so every double arrives bit
// for bit (NaN included). A thread with its own context (frame_threads.h)
// or an MPI rank (cluster/) that gets the plan evaluates a frame exactly as
// the process that owns the run would, and that one stores what it gets.

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/scene_match.h"
#include "fusion/temperature_field.h"
#include "pipeline/frame_distributor.h"
#include "pipeline/probe_calibration.h"
#include "pipeline/process_times.h"
#include "pipeline/processing_settings.h"
#include "storage/processing_store.h"
#include "storage/records.h"

namespace bosfuse::pipeline {

// Adds the wall time of its scope to `seconds`.
class AddTime {
 public:
  explicit AddTime(double& seconds) : seconds_(seconds) {}
  ~AddTime() { seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  AddTime(const AddTime&) = delete;
  AddTime& operator=(const AddTime&) = delete;

 private:
  double& seconds_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

template <class Work>
decltype(auto) timed(double& seconds, Work&& work) {
  const AddTime add(seconds);
  return work();
}

// A frame's evaluation, and its refusal when the frame does not show the
// reference's background (fusion/scene_match.h: a foreign or blank frame):
// then every vector is flagged (fusion::refuse_vectors) in the displacement
// field written, no temperature field is recovered, no probe sample is valid
// or holds a temperature, and the frame's stored summary names the reason
// under "refused".
struct CheckedEvaluation : fusion::EvaluationResult {
  std::optional<fusion::SceneMatch> refused;
};

// What every frame's evaluation needs besides the frame itself.
struct FrameContext {
  std::filesystem::path run_dir;
  std::string fields_dir;  // relative to the run folder; empty: fields are not written (the live page)
  storage::FrameRecord reference_frame;
  std::vector<storage::ChannelInfo> channels;
  std::vector<cv::Point2d> points;
  std::vector<std::int64_t> probe_ids;  // staged, one per channel
  cv::Mat reference;
  cv::Mat mask;
  ProcessingSettings settings;
  std::optional<fusion::BosGeometry> geometry;
  std::map<std::int64_t, ChannelCalibration> calibration;
  // One for the run: the reference is prepared once and the buffers of one
  // frame serve the next.
  std::unique_ptr<fusion::DisplacementEvaluator> evaluator;
  // One for the run too: the Poisson system's analysis is done once, and its
  // factor is reused while the unmeasured nodes stay. Frames are finished one
  // at a time (FinishingFrame waits for one before starting the next); the
  // solver serialises its calls besides, so the contexts of frames side by
  // side in one process share it (planned_frame_work_sharing).
  std::shared_ptr<fusion::TemperatureFieldSolver> temperature_solver;
  // The reference's moments, kept for every frame's scene check.
  std::shared_ptr<const fusion::SceneMatcher> scene;

  // The one place frames meet the evaluator: the full field, or only the
  // windows at the probes; a frame of another scene refused.
  CheckedEvaluation evaluate(const cv::Mat& measurement) const;
};

// A frame's results as one transaction stages them, and what making them
// took (decoding and evaluation when evaluate_and_finish made them, the
// temperature field, the field files).
struct FinishedFrame {
  storage::FrameRecord frame;
  nlohmann::ordered_json summary;  // the evaluation's, stored with the frame
  std::vector<storage::FieldRecord> fields;
  std::vector<storage::ProbeSampleRecord> samples;
  ProcessTimes times;
};

// The reference, the mask, the evaluator and the temperature solver of a
// context whose data is set (run_dir, fields_dir, reference_frame,
// settings, channels, points, probe_ids, calibration).
void load_frame_context(FrameContext& ctx);

// All of a frame's work after its evaluation: thread-safe against other
// frames' work with other contexts (it reads `ctx`, writes the frame's own files).
FinishedFrame finish_frame(const FrameContext& ctx, const storage::FrameRecord& frame,
                           const CheckedEvaluation& evaluated);

// A frame's samples at the probes exactly as finish_frame makes them, with
// nothing written: the shift at each probe (the full field interpolated
// there, or the probe's own window) and its temperature, by the calibration
// or else the physical model's temperature field. The live page shows these,
// so what it shows is what `process` will store. Each sample carries the
// σ of what it holds (nullopt where not estimated), of the probe's value —
// the bilinear interpolation of the four nodes around it — not of one node:
// the shift's σ the same weights on the nodes' σ (neighbouring windows
// overlap, so their errors are taken as fully correlated: an upper bound);
// the random σ of T under the physical model exactly through the solve
// (TemperatureFieldSolver::average_sigma_c, one solve per probe), under a
// calibration |slope| · σ of the shift; the systematic σ the Type-B budget
// (temperature_budget.h) with the run's [geometry.uncertainty] and the
// window-against-point term, under a calibration |shift| · σ of the slope.
std::vector<storage::ProbeSampleRecord> probe_samples(const FrameContext& ctx, const storage::FrameRecord& frame,
                                                      const CheckedEvaluation& evaluated);

// The reason a frame's stored summary gives for its refusal; nullopt for a
// frame that was not refused.
std::optional<std::string> refusal_of(const nlohmann::json& frame_summary);

// What gives the probes their temperatures: "calibration", "physical model",
// or none (probe mode without a calibration).
std::string temperature_source(const FrameContext& ctx);

// A frame from its file to its finished results, decoding and evaluation timed.
FinishedFrame evaluate_and_finish(const FrameContext& ctx, const storage::FrameRecord& frame);

// The plan: what another process needs to evaluate and finish any of
// `frames` as this one would — the context's data, not the store (a run
// folder on a shared filesystem is read by every node, its database written
// by one); the run folder by its absolute path.
Bytes plan_bytes(const FrameContext& ctx, const std::vector<storage::FrameRecord>& frames);
// The context a plan describes, loaded, and its frames.
std::pair<FrameContext, std::vector<storage::FrameRecord>> context_from_plan(const Bytes& plan);

Bytes finished_bytes(const FinishedFrame& frame);
FinishedFrame finished_from_bytes(const Bytes& bytes);

// The other processes' side of a distributed processing: the work of frame i
// of the plan (the run folder at the same path, as on a shared filesystem).
// Throws when this process cannot set up the plan's evaluation (the
// reference unreadable here, say).
FrameWork planned_frame_work(const Bytes& plan);
// The same, for another thread of this process: its context uses `solver`,
// the temperature solver of the plan's context here, instead of one of its
// own, so one analysis of the Poisson system (~1 s at 16 MP) serves every
// thread, and frames coming in sequence keep its factor longer.
FrameWork planned_frame_work_sharing(const Bytes& plan, std::shared_ptr<fusion::TemperatureFieldSolver> solver);

}  // namespace bosfuse::pipeline
