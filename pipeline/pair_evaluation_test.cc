#include "pipeline/pair_evaluation.h"

#include <gtest/gtest.h>

#include "tests/support/shifted_pair.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

class PairEvaluation : public ::testing::Test {
 protected:
  void SetUp() override {
    testing::write_shifted_pair(path("ref.png"), path("meas.png"), {96, 64}, 0.5, -0.25);
    testing::write_shifted_pair("", path("other.png"), {96, 64}, 0.5, -0.25, 2);  // another background: another scene
    options.set_grid(16, 8);
  }
  std::string path(const std::string& name) const { return (dir.path() / name).string(); }
  static std::size_t valid(const fusion::EvaluationResult& result) {
    std::size_t n = 0;
    for (const auto& v : result.field.vectors) n += v.valid() ? 1 : 0;
    return n;
  }

  testing::TempDir dir;
  fusion::EvaluatorOptions options;
};

TEST_F(PairEvaluation, AFullFieldOrOnlyTheProbesWindows) {
  const auto pair = read_image_pair(path("ref.png"), path("meas.png"));
  EXPECT_TRUE(pair.mask.empty());
  const auto field = evaluate_image_pair(pair, options);
  EXPECT_EQ(field.field.cols, (96 - 16) / 8 + 1);
  EXPECT_EQ(valid(field), field.field.vectors.size());
  const auto probes = evaluate_image_pair(pair, options, {{40, 32}, {56, 24}});
  ASSERT_EQ(probes.field.vectors.size(), 2u);
  EXPECT_NEAR(probes.field.vectors[0].u_px, 0.5, 0.05);
}

TEST_F(PairEvaluation, APairOfTwoScenesHasNoValidVector) {
  const auto result = evaluate_image_pair(read_image_pair(path("ref.png"), path("other.png")), options);
  EXPECT_FALSE(result.field.vectors.empty());
  EXPECT_EQ(valid(result), 0u);
}

TEST_F(PairEvaluation, AnUnreadableImageIsNamed) {
  try {
    read_image_pair(path("ref.png"), path("meas.png"), path("no-mask.png"));
    FAIL() << "a missing mask was read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no-mask.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bosfuse::pipeline
