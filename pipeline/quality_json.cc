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

}  // namespace bosfuse::pipeline
