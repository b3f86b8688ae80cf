#include "pipeline/pair_evaluation.h"

#include <spdlog/spdlog.h>

#include "fusion/scene_match.h"
#include "pipeline/evaluation_log.h"
#include "pipeline/image_io.h"

namespace bosfuse::pipeline {

ImagePair read_image_pair(const std::string& reference_path, const std::string& measurement_path,
                          const std::string& mask_path) {
  ImagePair pair;
  pair.reference_path = reference_path;
  pair.measurement_path = measurement_path;
  pair.reference = read_image(reference_path, "reference");
  pair.measurement = read_image(measurement_path, "measurement");
  if (!mask_path.empty()) pair.mask = read_image(mask_path, "mask");
  return pair;
}

fusion::EvaluationResult evaluate_image_pair(const ImagePair& pair, const fusion::EvaluatorOptions& options,
                                             const std::vector<cv::Point2d>& probes) {
  fusion::EvaluationResult result =
      probes.empty() ? fusion::evaluate_displacement(pair.reference, pair.measurement, options, pair.mask)
                     : fusion::probe_displacement(pair.reference, pair.measurement, probes, options, pair.mask);
  log_evaluation(result.summary);
  const auto scene = fusion::match_scene(pair.measurement, pair.reference);
  log_warnings(scene.warnings);
  if (!scene.same_scene()) {
    fusion::refuse_vectors(result);  // a pair of two scenes supports no vector
    spdlog::warn("{} against {}: {}; no vector is marked valid", pair.measurement_path, pair.reference_path,
                 scene.Describe());
  }
  return result;
}

}  // namespace bosfuse::pipeline
