#include "pipeline/sequence_evaluation.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "sim/synthetic_pair.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::pipeline {
namespace {

namespace fs = std::filesystem;

class SequenceEvaluation : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int k = 0; k < 2; ++k) {
      sim::PairOptions options;
      options.pattern.width_px = 96;
      options.pattern.height_px = 64;
      options.field = sim::DisplacementModel::uniform(0.5 * (k + 1), -0.25);
      const auto pair = sim::render_pair(options);
      if (k == 0) cv::imwrite(path("ref.png"), pair.reference);
      cv::imwrite(path("f_" + std::to_string(k + 1) + ".png"), pair.measurement);
    }
    fusion::EvaluatorOptions options;
    options.set_grid(16, 8);
    options_ = options;
  }
  std::string path(const std::string& name) const { return (dir.path() / name).string(); }
  static double mean_u(const fusion::DisplacementField& field) {
    double sum = 0;
    std::size_t n = 0;
    for (const auto& v : field.vectors) {
      if (v.valid()) sum += v.u_px, ++n;
    }
    return n ? sum / static_cast<double>(n) : -1;
  }

  testing::TempDir dir;
  fusion::EvaluatorOptions options_;
};

TEST_F(SequenceEvaluation, EachFrameGetsItsFieldOnTheGridKnownBeforehand) {
  SequenceEvaluator evaluator(path("ref.png"), options_);
  EXPECT_EQ(evaluator.grid().cols, (96 - 16) / 8 + 1);
  EXPECT_EQ(evaluator.grid().rows, (64 - 16) / 8 + 1);
  // In any order: nothing is kept between frames.
  for (const int k : {2, 1}) {
    const auto result = evaluator.evaluate(path("f_" + std::to_string(k) + ".png"));
    ASSERT_TRUE(result.ok()) << result.status;
    EXPECT_EQ(result.field.rows, evaluator.grid().rows);
    EXPECT_EQ(result.field.cols, evaluator.grid().cols);
    EXPECT_NEAR(mean_u(result.field), 0.5 * k, 0.03) << k;
    EXPECT_EQ(result.time.source, TimeSource::kFileModification);
  }
}

TEST_F(SequenceEvaluation, AFramesOwnProblemIsItsStatus) {
  SequenceEvaluator evaluator(path("ref.png"), options_);
  std::ofstream(path("junk.png")) << "not an image";
  const auto junk = evaluator.evaluate(path("junk.png"));
  EXPECT_FALSE(junk.ok());
  EXPECT_NE(junk.status.find("unreadable image"), std::string::npos) << junk.status;
  EXPECT_EQ(junk.time.source, TimeSource::kFileModification) << "the file exists: it has a time";
  EXPECT_EQ(junk.field.size(), 0u);

  cv::imwrite(path("small.png"), cv::imread(path("f_1.png"), cv::IMREAD_UNCHANGED)(cv::Rect(0, 0, 48, 32)).clone());
  const auto small = evaluator.evaluate(path("small.png"));
  EXPECT_EQ(small.status, "image size 48x32 differs from the reference's 96x64");

  const auto missing = evaluator.evaluate(path("gone.png"));
  EXPECT_EQ(missing.status, "no such file");
  EXPECT_EQ(missing.time.source, TimeSource::kNone);
}

TEST_F(SequenceEvaluation, AResultSurvivesItsBytesBitForBit) {
  SequenceEvaluator evaluator(path("ref.png"), options_);
  auto result = evaluator.evaluate(path("f_1.png"));
  ASSERT_TRUE(result.ok()) << result.status;
  result.field.vectors[3].u_px = std::numeric_limits<double>::quiet_NaN();  // as a failed node carries
  result.field.vectors[3].flag = fusion::VectorFlag::kNoPeak;
  const auto back = result_from_bytes(result_bytes(result));
  EXPECT_EQ(back.name, result.name);
  EXPECT_EQ(back.time.t_ns, result.time.t_ns);
  EXPECT_EQ(back.time.source, result.time.source);
  EXPECT_EQ(back.status, "ok");
  ASSERT_EQ(back.field.rows, result.field.rows);
  ASSERT_EQ(back.field.size(), result.field.size());
  for (std::size_t k = 0; k < result.field.size(); ++k) {
    const auto &a = result.field.vectors[k], &b = back.field.vectors[k];
    EXPECT_EQ(std::memcmp(&a.u_px, &b.u_px, sizeof(double)), 0) << k;  // NaN included
    EXPECT_EQ(a.v_px, b.v_px) << k;
    EXPECT_EQ(a.x_px, b.x_px) << k;
    EXPECT_EQ(a.peak_ratio, b.peak_ratio) << k;
    EXPECT_EQ(a.flag, b.flag) << k;
  }
  EXPECT_EQ(back.summary.BriefReport(), result.summary.BriefReport());

  std::ofstream(path("junk.png")) << "not an image";
  const auto failed = result_from_bytes(result_bytes(evaluator.evaluate(path("junk.png"))));
  EXPECT_NE(failed.status.find("unreadable image"), std::string::npos) << failed.status;
  EXPECT_EQ(failed.field.size(), 0u);
  EXPECT_THROW(result_from_bytes({1, 2, 3}), std::runtime_error);
}

TEST_F(SequenceEvaluation, ABadReferenceOrMaskOrWindowIsAnErrorBeforeAnyFrame) {
  std::ofstream(path("junk.png")) << "not an image";
  EXPECT_THROW(
      {
        try {
          SequenceEvaluator(path("junk.png"), options_);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("reference " + path("junk.png") + ": unreadable image"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      std::runtime_error);
  cv::imwrite(path("mask.png"), cv::Mat(10, 10, CV_8U, cv::Scalar(0)));
  EXPECT_THROW(SequenceEvaluator(path("ref.png"), options_, path("mask.png")), std::invalid_argument);
  auto wide = options_;
  wide.set_grid(128, 8);
  EXPECT_THROW(SequenceEvaluator(path("ref.png"), wide), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::pipeline
