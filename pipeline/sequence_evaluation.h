#pragma once
// Evaluating the frames of an image sequence (image_sequence.h) against one
// reference, one frame at a time. SequenceEvaluator reads and checks the
// reference and the mask once, and knows the grid every field will have
// before any frame is evaluated, so a writer can lay out its
// [frames, ny, nx] arrays first. A frame's own problem (unreadable, another
// size than the reference, not the same scene (fusion/scene_match.h), ...)
// is its result's status, not an exception:
// the other frames go on. evaluate() keeps the reference prepared and its
// buffers from frame to frame (fusion::DisplacementEvaluator) and takes the
// frames in any order: workers (threads, or MPI ranks) each hold their own
// SequenceEvaluator and may take any frame index.

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "fusion/displacement_evaluator.h"
#include "fusion/scene_match.h"
#include "pipeline/image_sequence.h"

namespace bosfuse::pipeline {

struct SequenceFrameResult {
  std::string name;                 // the frame's path as listed
  FrameTime time;                   // known whenever the file exists, even if it cannot be evaluated
  std::string status = "ok";        // "ok", or why the frame has no field (the file is not repeated)
  fusion::DisplacementField field;  // on the evaluator's grid() when ok
  fusion::EvaluationSummary summary;

  bool ok() const { return status == "ok"; }
};

class SequenceEvaluator {
 public:
  // Throws std::runtime_error naming the file when the reference or the mask
  // cannot be read, and std::invalid_argument when the options do not fit
  // the reference (a window larger than the image, a ROI outside it, a mask
  // of another size) or when evaluating a frame of the reference's size needs
  // more memory than this process can get (fusion::InsufficientMemory):
  // nothing about the sequence is known to be usable then.
  SequenceEvaluator(const std::string& reference_path, fusion::EvaluatorOptions options,
                    const std::string& mask_path = {});

  SequenceFrameResult evaluate(const std::string& frame_path);

  // Window centres of every field: cols × rows nodes from (x0, y0) every step.
  const fusion::GridGeometry& grid() const { return grid_; }
  cv::Size image_size() const { return reference_.size(); }
  const fusion::EvaluatorOptions& options() const { return options_; }

 private:
  cv::Mat reference_;
  cv::Mat mask_;
  fusion::EvaluatorOptions options_;
  fusion::GridGeometry grid_;
  std::optional<fusion::DisplacementEvaluator> evaluator_;  // made once the reference is checked
  std::optional<fusion::SceneMatcher> scene_;
};

// A frame's result as bytes and back, bit for bit, so an MPI rank can send
// it to the one that writes the file (frame_distributor.h).
std::vector<std::uint8_t> result_bytes(const SequenceFrameResult& result);
// Throws std::runtime_error on bytes not made by result_bytes().
SequenceFrameResult result_from_bytes(const std::vector<std::uint8_t>& bytes);

}  // namespace bosfuse::pipeline
