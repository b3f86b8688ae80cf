#include "pipeline/sequence_evaluation.h"

#include <fmt/format.h>

#include <fstream>
#include <stdexcept>

#include "acquisition/image_file.h"
#include "fusion/evaluation.h"
#include "fusion/image_input.h"
#include "pipeline/image_io.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fs::exists(path) ? "cannot open the file" : "no such file");
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw std::runtime_error("cannot read the file");
  return bytes;
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
  evaluator_->check_memory();
}

SequenceFrameResult SequenceEvaluator::evaluate(const std::string& frame_path) {
  SequenceFrameResult result;
  result.name = frame_path;
  try {
    const std::vector<std::uint8_t> bytes = read_bytes(frame_path);
    result.time = frame_time(frame_path, bytes);
    const cv::Mat image = acquisition::decode_image(bytes, frame_path);
    if (image.empty())
      throw std::runtime_error("unreadable image (not a PNG, JPEG, TIFF, BMP or PNM image bosfuse can decode)");
    if (image.size() != reference_.size()) {
      throw std::runtime_error(fmt::format("image size {}x{} differs from the reference's {}x{}", image.cols,
                                           image.rows, reference_.cols, reference_.rows));
    }
    fusion::EvaluationResult evaluated = evaluator_->evaluate(image);
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

}  // namespace bosfuse::pipeline
