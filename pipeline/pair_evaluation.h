#pragma once
// One image pair evaluated as `bosfuse evaluate REF MEAS` does it: the
// reference, the measurement and the mask read (image_io.h), then the full
// field or only the windows at given points, and a pair of two scenes
// (fusion/scene_match.h) refused: none of its vectors is valid and a
// warning names both files. Use it for a single pair; the frames of a
// sequence against one reference are sequence_run.h's.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fusion/displacement_evaluator.h"

namespace bosfuse::pipeline {

struct ImagePair {
  std::string reference_path, measurement_path;  // as given, for messages
  cv::Mat reference, measurement;
  cv::Mat mask;  // empty: none
};

// Throws std::runtime_error naming the file that cannot be read; an empty
// `mask_path` is no mask.
ImagePair read_image_pair(const std::string& reference_path, const std::string& measurement_path,
                          const std::string& mask_path = {});

// `probes` empty: the full field on the options' grid; else the windows
// centred there, in their order. Throws std::invalid_argument when the
// options do not fit the images.
fusion::EvaluationResult evaluate_image_pair(const ImagePair& pair, const fusion::EvaluatorOptions& options,
                                             const std::vector<cv::Point2d>& probes = {});

}  // namespace bosfuse::pipeline
