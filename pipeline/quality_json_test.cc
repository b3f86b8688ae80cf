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

}  // namespace
}  // namespace bosfuse::pipeline
