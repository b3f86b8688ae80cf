#include "pipeline/sequence_evaluation.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <type_traits>

#include "acquisition/cameras/image_file.h"
#include "fusion/evaluation.h"
#include "fusion/image_input.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/image_io.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;
using sorted_json = nlohmann::json;  // keys sorted, unlike the ordered_json the rest of pipeline writes

// The frame's bytes, read whole only once its size and header pass the
// image limits (acquisition/cameras/image_file.h); empty for a file of no image
// format bosfuse reads. `time` is the frame's time even when it is refused.
std::vector<std::uint8_t> read_frame_bytes(const std::string& path, FrameTime& time) {
  std::error_code error;
  if (!fs::exists(path, error)) throw std::runtime_error("no such file");
  try {
    return acquisition::read_image_bytes(path);
  } catch (...) {
    time = frame_time(path, {});
    throw;
  }
}

int first_window_px(const fusion::EvaluatorOptions& options) {
  return options.method == fusion::Method::kCrossCorrelation ? options.xcorr.window_px_per_pass().front()
                                                             : options.flow.window_px;
}

}  // namespace

SequenceEvaluator::SequenceEvaluator(const std::string& reference_path, fusion::EvaluatorOptions options,
                                     const std::string& mask_path)
    : options_(std::move(options)) {
  if (const auto problem = options_.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  reference_ = read_image(reference_path, "reference");
  if (!mask_path.empty()) mask_ = read_image(mask_path, "mask");
  fusion::check_image_pair(reference_, reference_, mask_);  // the mask's size
  const cv::Rect roi = fusion::effective_roi(options_.xcorr.roi, reference_.size());
  fusion::check_window_fits(first_window_px(options_), roi.size());
  grid_ = fusion::evaluation_grid(roi, options_.xcorr.window_px, options_.xcorr.step_px);
  evaluator_.emplace(reference_, options_, mask_);
  if (const std::string account = evaluator_->check_memory(); !account.empty()) spdlog::debug("{}", account);
  scene_.emplace(reference_);
}

SequenceFrameResult SequenceEvaluator::evaluate(const std::string& frame_path) {
  SequenceFrameResult result;
  result.name = frame_path;
  try {
    const std::vector<std::uint8_t> bytes = read_frame_bytes(frame_path, result.time);
    result.time = frame_time(frame_path, bytes);
    const cv::Mat image = acquisition::decode_image(bytes, frame_path);
    if (image.empty())
      throw std::runtime_error("unreadable image (not a PNG, JPEG, TIFF, BMP or PNM image bosfuse can decode)");
    if (image.size() != reference_.size()) {
      throw std::runtime_error(fmt::format("image size {}x{} differs from the reference's {}x{}", image.cols,
                                           image.rows, reference_.cols, reference_.rows));
    }
    // Another scene supports no vector: the frame's status says so, as for an unreadable one.
    const auto scene = scene_->match(image);
    log_warnings(scene.warnings);
    if (!scene.same_scene()) throw std::runtime_error(scene.Describe());
    fusion::EvaluationResult evaluated = evaluator_->evaluate(image);
    log_evaluation(evaluated.summary);
    if (evaluated.field.rows != grid_.rows || evaluated.field.cols != grid_.cols) {
      throw std::logic_error(fmt::format("the field has {}x{} nodes, not the {}x{} of the sequence's grid",
                                         evaluated.field.cols, evaluated.field.rows, grid_.cols, grid_.rows));
    }
    result.field = std::move(evaluated.field);
    result.summary = std::move(evaluated.summary);
  } catch (const std::exception& e) {
    result.status = e.what();
    if (result.status.empty() || result.status == "ok") result.status = "failed without a message";
    result.field = {};
  }
  return result;
}

namespace {

// Every field, in one order both ways (ranks of one job run one build).
sorted_json summary_json(const fusion::EvaluationSummary& s) {
  return {s.method,        s.passes_run,         s.window_px_per_pass,  s.converged,          s.last_change_px,
          s.refined_fraction, s.vectors,         s.valid,               s.outliers_replaced,  s.no_texture,
          s.masked,        s.out_of_roi,         s.no_peak,             s.beyond_search,      s.max_shift_px,
          s.first_window_px, s.search_from_scene, s.search_widened,     s.search_beyond_reach, s.first_pass_windows,
          s.first_pass_on_bound, s.seconds, s.search_stored};
}

fusion::EvaluationSummary summary_from_json(const sorted_json& j) {
  fusion::EvaluationSummary s;
  std::size_t i = 0;
  const auto next = [&](auto& field) { j.at(i++).get_to(field); };
  next(s.method), next(s.passes_run), next(s.window_px_per_pass), next(s.converged), next(s.last_change_px);
  next(s.refined_fraction), next(s.vectors), next(s.valid), next(s.outliers_replaced), next(s.no_texture);
  next(s.masked), next(s.out_of_roi), next(s.no_peak), next(s.beyond_search), next(s.max_shift_px);
  next(s.first_window_px), next(s.search_from_scene), next(s.search_widened), next(s.search_beyond_reach);
  next(s.first_pass_windows), next(s.first_pass_on_bound), next(s.seconds), next(s.search_stored);
  return s;
}

// The vectors as they lie in memory: ranks of one job run one build of bosfuse.
static_assert(std::is_trivially_copyable_v<fusion::DisplacementVector>);

std::vector<std::uint8_t> vectors_binary(const std::vector<fusion::DisplacementVector>& vectors) {
  std::vector<std::uint8_t> out(vectors.size() * sizeof(fusion::DisplacementVector));
  if (!vectors.empty()) std::memcpy(out.data(), vectors.data(), out.size());
  return out;
}

std::vector<fusion::DisplacementVector> vectors_from_binary(const sorted_json::binary_t& bytes) {
  if (bytes.size() % sizeof(fusion::DisplacementVector) != 0) throw std::runtime_error("a truncated field");
  std::vector<fusion::DisplacementVector> out(bytes.size() / sizeof(fusion::DisplacementVector));
  if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}

}  // namespace

std::vector<std::uint8_t> result_bytes(const SequenceFrameResult& r) {
  return sorted_json::to_cbor(sorted_json{{"name", r.name},
                            {"t_ns", r.time.t_ns ? sorted_json(*r.time.t_ns) : sorted_json(nullptr)},
                            {"time_source", static_cast<int>(r.time.source)},
                            {"status", r.status},
                            {"rows", r.field.rows},
                            {"cols", r.field.cols},
                            {"vectors", sorted_json::binary(vectors_binary(r.field.vectors))},
                            {"summary", summary_json(r.summary)}});
}

SequenceFrameResult result_from_bytes(const std::vector<std::uint8_t>& bytes) {
  try {
    const sorted_json j = sorted_json::from_cbor(bytes);
    SequenceFrameResult r;
    r.name = j.at("name").get<std::string>();
    if (!j.at("t_ns").is_null()) r.time.t_ns = j.at("t_ns").get<std::int64_t>();
    r.time.source = static_cast<TimeSource>(j.at("time_source").get<int>());
    r.status = j.at("status").get<std::string>();
    r.field.rows = j.at("rows").get<int>();
    r.field.cols = j.at("cols").get<int>();
    r.field.vectors = vectors_from_binary(j.at("vectors").get_binary());
    r.summary = summary_from_json(j.at("summary"));
    if (r.field.vectors.size() != static_cast<std::size_t>(r.field.rows) * r.field.cols) {
      throw std::runtime_error("a field of another size than its grid");
    }
    return r;
  } catch (const sorted_json::exception& e) {
    throw std::runtime_error(std::string("a sequence frame's result that cannot be read: ") + e.what());
  }
}

}  // namespace bosfuse::pipeline
