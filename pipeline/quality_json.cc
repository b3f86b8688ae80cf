#include "pipeline/quality_json.h"

namespace bosfuse::pipeline {

nlohmann::ordered_json to_json(const fusion::QualityIndex& q) {
  return {{"q_l", q.q_l},
          {"q_c", q.q_c},
          {"q_mod", q.q_mod},
          {"mean_image", q.mean_image},
          {"mean_reference", q.mean_reference},
          {"std_image", q.std_image},
          {"std_reference", q.std_reference}};
}

fusion::QualityIndex quality_from_json(const nlohmann::json& j) {
  return {j.at("q_l").get<double>(),          j.at("q_c").get<double>(),       j.at("q_mod").get<double>(),
          j.at("mean_image").get<double>(),   j.at("mean_reference").get<double>(), j.at("std_image").get<double>(),
          j.at("std_reference").get<double>()};
}

nlohmann::ordered_json to_json(const fusion::SceneMatch& m) {
  nlohmann::ordered_json j = to_json(m.quality);
  j["verdict"] = fusion::to_string(m.verdict);
  j["scene_correlation"] = m.correlation;
  j["scene_tiles"] = m.tiles;
  j["scene_thresholds"] = {{"min_correlation", m.options.min_correlation},
                           {"min_texture", m.options.min_texture},
                           {"good_q_mod", m.options.good_q_mod},
                           {"usable_q_mod", m.options.usable_q_mod},
                           {"blur_sigma_px", m.options.blur_sigma_px},
                           {"max_shift_px", m.options.max_shift_px},
                           {"tile_px", m.options.tile_px}};
  return j;
}

fusion::SceneMatch scene_match_from_json(const nlohmann::json& j) {
  fusion::SceneMatch m;
  m.quality = quality_from_json(j);
  m.verdict = fusion::scene_verdict_from_string(j.at("verdict").get<std::string>());
  m.correlation = j.at("scene_correlation").get<double>();
  m.tiles = j.at("scene_tiles").get<int>();
  const auto& t = j.at("scene_thresholds");
  m.options.min_correlation = t.at("min_correlation").get<double>();
  m.options.min_texture = t.at("min_texture").get<double>();
  m.options.good_q_mod = t.at("good_q_mod").get<double>();
  m.options.usable_q_mod = t.at("usable_q_mod").get<double>();
  m.options.blur_sigma_px = t.at("blur_sigma_px").get<double>();
  m.options.max_shift_px = t.at("max_shift_px").get<int>();
  m.options.tile_px = t.at("tile_px").get<int>();
  return m;
}

}  // namespace bosfuse::pipeline
