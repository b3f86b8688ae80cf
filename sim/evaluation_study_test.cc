#include "sim/evaluation_study.h"

#include <gtest/gtest.h>

namespace bosfuse::sim {
namespace {

TEST(EvaluationStudy, RiseWidthOfARamp) {
  std::vector<double> x, p;
  for (int i = 0; i <= 100; ++i) {
    x.push_back(i);
    p.push_back(std::clamp((i - 40) / 20.0, 0.0, 1.0));  // 0 → 1 between 40 and 60
  }
  EXPECT_NEAR(rise_width_px(x, p, 0, 1), 16.0, 1e-9);
}

TEST(EvaluationStudy, UniformStudyMeasuresAccuracyAndSpeed) {
  StudyCase study;
  study.size_px = 128;
  study.shifts_px = {0.25, 0.75};
  const StudyResult r = run_uniform_study(study);
  EXPECT_GT(r.compared, 100u);
  EXPECT_GE(r.valid, r.compared);
  EXPECT_GT(r.vectors_per_s, 0);
  EXPECT_LT(r.rms_px, 0.05);
  EXPECT_LE(r.rms_px, r.p95_px * 1.5);
  // Without deformation the same pair is measured visibly worse (peak
  // locking): the study resolves the difference it is meant to show.
  study.evaluator.xcorr.passes = 1;
  const StudyResult single = run_uniform_study(study);
  EXPECT_GT(single.rms_px, 1.5 * r.rms_px);
}

TEST(EvaluationStudy, StepRiseWidthShrinksWithTheWindow) {
  fusion::EvaluatorOptions options;
  options.set_grid(32, 1);
  const StepResult wide = run_step_study(options);
  options.set_grid(8, 1);
  const StepResult narrow = run_step_study(options);
  EXPECT_GT(wide.rise_width_px, narrow.rise_width_px);
  EXPECT_LT(narrow.rise_width_px, 12);
  EXPECT_LT(wide.plateau_error_px, 0.05);
}

}  // namespace
}  // namespace bosfuse::sim
