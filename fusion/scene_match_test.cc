#include "fusion/scene_match.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

sim::PairOptions pair_options(sim::DisplacementModel field, std::uint64_t seed = 3) {
  sim::PairOptions options;
  options.pattern.width_px = 256;
  options.pattern.height_px = 192;
  options.pattern.seed = seed;
  options.field = field;
  options.noise_std = 0.02;
  return options;
}

// A matching pair: the same background behind a BOS displacement, with
// noise: uniform shifts of 0, 2 and 6.5 px, the last with more noise, and a
// plume whose shift changes by 6.5 px within 40 px (the hardest for a tile).
TEST(SceneMatch, TheSameBackgroundShiftedByAPlumeWithNoiseIsTheSameScene) {
  struct Case {
    sim::DisplacementModel field;
    double noise;
    double least_correlation;
  };
  const std::vector<Case> cases{{sim::DisplacementModel::uniform(0, 0), 0.02, 0.9},
                                {sim::DisplacementModel::uniform(2, 0), 0.02, 0.9},
                                {sim::DisplacementModel::uniform(5.3, -3.7), 0.02, 0.9},  // |d| = 6.5 px
                                {sim::DisplacementModel::uniform(5.3, -3.7), 0.08, 0.8},
                                {sim::DisplacementModel::bump_gradient(128, 96, 40, 6.5), 0.02, 0.65}};
  for (const auto& c : cases) {
    auto options = pair_options(c.field);
    options.noise_std = c.noise;
    const auto pair = sim::render_pair(options);
    const SceneMatch m = match_scene(pair.measurement, pair.reference);
    EXPECT_TRUE(m.same_scene()) << m.Describe();
    EXPECT_GT(m.correlation, c.least_correlation) << m.Describe();
    EXPECT_EQ(m.verdict, SceneVerdict::kGood) << m.Describe();
    EXPECT_GT(m.tiles, 1);
  }
}

TEST(SceneMatch, AnUnrelatedBackgroundIsNotTheSameSceneThoughItsQModIsHigh) {
  const auto a = sim::render_pair(pair_options(sim::DisplacementModel::uniform(0, 0), 3));
  const auto b = sim::render_pair(pair_options(sim::DisplacementModel::uniform(0, 0), 4));
  const SceneMatch m = match_scene(b.measurement, a.reference);
  for (std::uint64_t seed = 5; seed < 12; ++seed) {  // chance correlations stay well below the threshold
    const auto other = sim::render_pair(pair_options(sim::DisplacementModel::uniform(0, 0), seed));
    EXPECT_LT(match_scene(other.measurement, a.reference).correlation, 0.35) << "seed " << seed;
  }
  EXPECT_GT(m.quality.q_mod, 0.9) << "the case Q_mod cannot tell";
  EXPECT_EQ(m.verdict, SceneVerdict::kNotSameScene) << m.Describe();
  EXPECT_LT(m.correlation, m.options.min_correlation);
  EXPECT_FALSE(m.same_scene());
  EXPECT_NE(m.Describe().find("scene correlation"), std::string::npos) << m.Describe();
  EXPECT_NE(m.Describe().find("< 0.50"), std::string::npos) << m.Describe();
}

TEST(SceneMatch, TwoFeaturelessImagesHaveNoTextureNeverGood) {
  const cv::Mat grey(120, 160, CV_8U, cv::Scalar(128));
  const SceneMatch flat = match_scene(grey, grey);
  EXPECT_NEAR(flat.quality.q_mod, 1.0, 1e-12) << "Q_mod alone calls this perfect";
  EXPECT_EQ(flat.verdict, SceneVerdict::kNoTexture) << flat.Describe();
  EXPECT_FALSE(flat.same_scene());

  const auto pair = sim::render_pair(pair_options(sim::DisplacementModel::uniform(0, 0)));
  const cv::Mat black = cv::Mat::zeros(pair.reference.size(), CV_8U);
  EXPECT_EQ(match_scene(black, pair.reference).verdict, SceneVerdict::kNoTexture) << "a blank frame";
}

// The paper's bands, hit by the same pattern with its contrast scaled by k
// around its mean: Q_C = 2k/(1 + k²), Q_L = 1.
TEST(SceneMatch, TheQModBandsAreGoodUsableAndPoor) {
  const auto pair = sim::render_pair(pair_options(sim::DisplacementModel::uniform(1, 0)));
  cv::Mat measurement;
  pair.measurement.convertTo(measurement, CV_32F, 1.0 / 255);
  const double mean = cv::mean(measurement)[0];
  const std::vector<std::pair<double, SceneVerdict>> cases{
      {0.6, SceneVerdict::kGood}, {0.15, SceneVerdict::kUsable}, {0.03, SceneVerdict::kPoor}};
  for (const auto& [k, expected] : cases) {
    const cv::Mat scaled = (measurement - mean) * k + mean;
    const SceneMatch m = match_scene(scaled, pair.reference);
    EXPECT_EQ(m.verdict, expected) << "k = " << k << ": " << m.Describe();
    EXPECT_NEAR(m.quality.q_c, 2 * k / (1 + k * k), 0.02);
  }
}

TEST(SceneMatch, AFrameOfAnotherSizeIsComparedWithTheReferenceResized) {
  const auto pair = sim::render_pair(pair_options(sim::DisplacementModel::uniform(0, 0)));
  cv::Mat half;
  cv::resize(pair.measurement, half, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  EXPECT_TRUE(match_scene(half, pair.reference).same_scene());
}

TEST(SceneMatch, RefusedVectorsAreNoneOfThemValid) {
  EvaluationResult result;
  result.field.rows = 1;
  result.field.cols = 3;
  result.field.vectors.resize(3);
  result.field.vectors[1].flag = VectorFlag::kMasked;
  result.field.vectors[2].flag = VectorFlag::kOutlierReplaced;
  result.summary.valid = 1;
  refuse_vectors(result);
  EXPECT_EQ(result.field.count_valid(), 0u);
  EXPECT_EQ(result.summary.valid, 0u);
  EXPECT_EQ(result.summary.no_peak, 2u);
  EXPECT_EQ(result.field.vectors[1].flag, VectorFlag::kMasked) << "a masked window stays masked";
}

TEST(SceneMatch, OptionsOutOfRangeAreRefused) {
  EXPECT_EQ(SceneMatchOptions{}.Validate(), "");
  SceneMatchOptions o;
  o.min_correlation = 1.5;
  EXPECT_NE(o.Validate(), "");
  o = {};
  o.good_q_mod = 0.05;  // below usable
  EXPECT_NE(o.Validate(), "");
  o = {};
  o.tile_px = 2;
  EXPECT_THROW(SceneMatcher(cv::Mat(64, 64, CV_8U, cv::Scalar(1)), o), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fusion
