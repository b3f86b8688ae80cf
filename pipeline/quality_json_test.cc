#include "pipeline/quality_json.h"

#include <gtest/gtest.h>

namespace bosfuse::pipeline {
namespace {

TEST(QualityJson, WhatIsWrittenComesBack) {
  const fusion::QualityIndex q{0.9, 0.8, 0.72, 0.45, 0.5, 0.21, 0.25};
  const auto back = quality_from_json(nlohmann::json::parse(to_json(q).dump()));
  EXPECT_EQ(back.q_l, q.q_l);
  EXPECT_EQ(back.q_c, q.q_c);
  EXPECT_EQ(back.q_mod, q.q_mod);
  EXPECT_EQ(back.mean_image, q.mean_image);
  EXPECT_EQ(back.mean_reference, q.mean_reference);
  EXPECT_EQ(back.std_image, q.std_image);
  EXPECT_EQ(back.std_reference, q.std_reference);
  EXPECT_THROW(quality_from_json(nlohmann::json{{"q_l", 1}}), nlohmann::json::exception);
}

TEST(QualityJson, TheVerdictAndItsThresholdsComeBackBesideTheIndex) {
  fusion::SceneMatch m;
  m.verdict = fusion::SceneVerdict::kNotSameScene;
  m.correlation = 0.145;
  m.tiles = 12;
  m.quality = {0.99, 0.98, 0.97, 0.45, 0.46, 0.3, 0.31};
  m.options.min_correlation = 0.4;
  m.options.good_q_mod = 0.6;
  const auto j = nlohmann::json::parse(to_json(m).dump());
  EXPECT_EQ(j.at("verdict"), "not the same scene");
  EXPECT_EQ(quality_from_json(j).q_mod, 0.97) << "the index's own keys are kept";
  const auto back = scene_match_from_json(j);
  EXPECT_EQ(back.verdict, m.verdict);
  EXPECT_EQ(back.correlation, m.correlation);
  EXPECT_EQ(back.tiles, m.tiles);
  EXPECT_EQ(back.options.min_correlation, 0.4);
  EXPECT_EQ(back.options.good_q_mod, 0.6);
  EXPECT_EQ(back.options.usable_q_mod, m.options.usable_q_mod);
  EXPECT_EQ(back.options.min_texture, m.options.min_texture);
  auto wrong = j;
  wrong["verdict"] = "excellent";
  EXPECT_THROW(scene_match_from_json(wrong), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::pipeline
