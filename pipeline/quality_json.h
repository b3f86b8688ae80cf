#pragma once
// The image quality index (fusion/image_quality.h) as JSON, in one layout for
// `bosfuse quality --json` and the quality a processing stores with its
// results (read back by the report): q_l, q_c, q_mod and the images' means
// and standard deviations (of full scale). The reader lives here, next to
// the writer, so a key cannot drift between them. The scene verdict
// (fusion/scene_match.h) has its own keys beside the index's: verdict,
// scene_correlation, scene_tiles and the thresholds it was judged by.

#include <nlohmann/json.hpp>

#include "fusion/image_quality.h"
#include "fusion/scene_match.h"

namespace bosfuse::pipeline {

nlohmann::ordered_json to_json(const fusion::QualityIndex& index);
// Throws nlohmann::json::exception on a document of another layout.
fusion::QualityIndex quality_from_json(const nlohmann::json& j);

// The index's keys (to_json above) and the verdict's.
nlohmann::ordered_json to_json(const fusion::SceneMatch& match);
// Throws nlohmann::json::exception on a document of another layout,
// std::invalid_argument on an unknown verdict.
fusion::SceneMatch scene_match_from_json(const nlohmann::json& j);

}  // namespace bosfuse::pipeline
