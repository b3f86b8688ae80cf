#pragma once
// The image quality index (fusion/image_quality.h) as JSON, in one layout for
// `bosfuse quality --json` and the quality a processing stores with its
// results (read back by the report): q_l, q_c, q_mod and the images' means
// and standard deviations (of full scale). The reader lives here, next to
// the writer, so a key cannot drift between them.

#include <nlohmann/json.hpp>

#include "fusion/image_quality.h"

namespace bosfuse::pipeline {

nlohmann::ordered_json to_json(const fusion::QualityIndex& index);
// Throws nlohmann::json::exception on a document of another layout.
fusion::QualityIndex quality_from_json(const nlohmann::json& j);

}  // namespace bosfuse::pipeline
