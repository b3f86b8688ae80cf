#include "pipeline/sequence_run.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "pipeline/image_sequence.h"

namespace bosfuse::pipeline {
namespace {

Bytes sequence_plan(const std::vector<std::string>& frames, const std::string& settings) {
  return nlohmann::json::to_cbor(nlohmann::json{{"frames", frames}, {"settings", settings}});
}

// Frames [0, count) evaluated here or by the distributor's ranks, each
// handed to `take` in order; returns how many were taken before a stop.
std::size_t evaluate_frames(const SequenceRunOptions& options, SequenceEvaluator& evaluator,
                            const std::vector<std::string>& frames,
                            const std::function<void(std::size_t, const SequenceFrameResult&)>& take) {
  const std::size_t count = frames.size();
  if (options.distributor) {
    return options.distributor->run(
        sequence_plan(frames, sequence_settings_json(options)), count,
        [&](std::size_t i) { return result_bytes(evaluator.evaluate(frames[i])); },
        [&](std::size_t i, const Bytes& bytes) { take(i, result_from_bytes(bytes)); }, options.stop);
  }
  std::size_t taken = 0;
  for (; taken < count && !(options.stop && *options.stop); ++taken) take(taken, evaluator.evaluate(frames[taken]));
  return taken;
}

}  // namespace

std::string SequenceRunOptions::Validate() const {
  if (reference.empty()) return "a sequence needs a reference image";
  if (sequence.empty()) return "a sequence needs a folder or a pattern of frames";
  if (settings.probes_only) return "a sequence is evaluated in full fields, not in probe mode";
  return settings.evaluator.Validate();
}

SequenceRunSummary run_sequence(const SequenceRunOptions& options, SequenceSink& sink) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  // The reference, the mask and the settings are checked before anything is written.
  SequenceEvaluator evaluator(options.reference, options.settings.evaluator, options.settings.mask);
  const auto sequence = list_image_sequence(options.sequence, {options.reference, options.settings.mask});
  for (const auto& file : sequence.left_out) spdlog::info("{}: the reference or the mask, not a frame", file);
  sink.open({options.reference, sequence_settings_json(options), sequence.frames, evaluator.grid()});

  SequenceRunSummary summary;
  summary.frames = sequence.frames.size();
  auto take = [&](std::size_t i, const SequenceFrameResult& result) {
    if (!result.ok()) {
      ++summary.frames_failed;
      sink.warn(fmt::format("frame {}: {}", result.name, result.status));
    } else {
      spdlog::debug("{}: {}", result.name, result.summary.BriefReport());
    }
    sink.write(i, summary.frames, result);
  };
  summary.frames_taken = evaluate_frames(options, evaluator, sequence.frames, take);
  if (!summary.complete()) return summary;
  sink.frames_done();
  if (options.distributor) spdlog::info("{}", options.distributor->brief_report());
  sink.commit();
  return summary;
}

std::string sequence_settings_json(const SequenceRunOptions& options) {
  const ProcessingSettings& settings = options.settings;
  auto j = to_json(settings);
  j.erase("mode");
  j.erase("probe_context_nodes");
  j.erase("geometry");
  j["first_window_px"] = settings.evaluator.xcorr.first_window_px;
  j["subpixel"] = options.subpixel;
  j["interpolator"] = options.interpolator;
  j["dis_preset"] = fusion::to_string(settings.evaluator.flow.dis_preset);
  j["source"] = settings.source;
  return j.dump();
}

FrameWork sequence_frame_work(const SequenceRunOptions& options, const Bytes& plan) {
  const auto j = nlohmann::json::from_cbor(plan);
  if (j.at("settings").get<std::string>() != sequence_settings_json(options)) {
    throw std::runtime_error("the settings resolved here differ from rank 0's: is " +
                             (options.settings_file.empty() ? std::string("the mask") : options.settings_file) +
                             " the same file on every node?");
  }
  auto evaluator =
      std::make_shared<SequenceEvaluator>(options.reference, options.settings.evaluator, options.settings.mask);
  auto frames = std::make_shared<std::vector<std::string>>(j.at("frames").get<std::vector<std::string>>());
  return [evaluator, frames](std::size_t i) { return result_bytes(evaluator->evaluate(frames->at(i))); };
}

}  // namespace bosfuse::pipeline
