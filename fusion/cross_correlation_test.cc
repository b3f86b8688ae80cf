#include "fusion/cross_correlation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "fusion/adaptive_refinement.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

sim::SyntheticPair render(const sim::DisplacementModel& field, int size_px = 256, double noise = 0.01,
                          std::uint64_t seed = 3) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = size_px;
  options.pattern.dot_diameter_px = 3;
  options.pattern.coverage = 0.5;
  options.pattern.seed = seed;
  options.noise_std = noise;
  options.field = field;
  return sim::render_pair(options);
}

struct ErrorStats {
  double mean_u = 0, mean_v = 0, rms = 0;
  std::size_t compared = 0;
};

// Errors against the window-averaged truth over the valid vectors for which
// `include` holds.
template <typename Include>
ErrorStats errors(const DisplacementField& field, const sim::DisplacementModel& truth, int window_px, Include include) {
  ErrorStats s;
  double sum_sq = 0;
  for (const auto& vec : field.vectors) {
    if (!vec.valid() || !include(vec)) continue;
    const cv::Point2d expected = truth.window_mean(vec.x_px, vec.y_px, window_px);
    s.mean_u += vec.u_px - expected.x;
    s.mean_v += vec.v_px - expected.y;
    sum_sq += std::pow(vec.u_px - expected.x, 2) + std::pow(vec.v_px - expected.y, 2);
    ++s.compared;
  }
  if (s.compared == 0) return s;
  s.mean_u /= s.compared;
  s.mean_v /= s.compared;
  s.rms = std::sqrt(sum_sq / s.compared);
  return s;
}

ErrorStats errors(const DisplacementField& field, const sim::DisplacementModel& truth, int window_px) {
  return errors(field, truth, window_px, [](const auto&) { return true; });
}

bool all_finite(const DisplacementField& field) {
  for (const auto& v : field.vectors) {
    if (!std::isfinite(v.u_px) || !std::isfinite(v.v_px) || !std::isfinite(v.peak_ratio)) return false;
  }
  return true;
}

TEST(CrossCorrelation, RecoversAUniformSubpixelShift) {
  for (const cv::Point2d shift : {cv::Point2d(0.3, -0.7), cv::Point2d(1.45, 0.15)}) {
    const auto pair = render(sim::DisplacementModel::uniform(shift.x, shift.y));
    const auto result = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
    const auto e = errors(result.field, pair.truth, 16);
    EXPECT_GT(e.compared, 0.95 * result.field.size()) << result.summary.BriefReport();
    EXPECT_LT(std::abs(e.mean_u), 0.01) << shift;
    EXPECT_LT(std::abs(e.mean_v), 0.01) << shift;
    EXPECT_LT(e.rms, 0.03) << shift;
  }
}

TEST(CrossCorrelation, SubpixelEstimatorsAgreeWithoutDeformation) {
  const auto pair = render(sim::DisplacementModel::uniform(0.35, 0.0));
  for (const auto estimator : {SubpixelEstimator::kGaussian3Point, SubpixelEstimator::kGaussian2dFit}) {
    XcorrOptions options;
    options.passes = 1;
    options.subpixel = estimator;
    const auto e = errors(evaluate_xcorr(pair.reference, pair.measurement, options).field, pair.truth, 16);
    EXPECT_LT(std::abs(e.mean_u), 0.06);
    EXPECT_LT(e.rms, 0.1);
  }
}

TEST(CrossCorrelation, RecoversTheStepAwayFromIt) {
  const auto pair = render(sim::DisplacementModel::step(64, 1.0, 0.0), 128);
  XcorrOptions options;
  options.window_px = 16;
  options.step_px = 4;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  const auto far_left = errors(result.field, pair.truth, 16, [](const auto& v) { return v.x_px < 48; });
  const auto far_right = errors(result.field, pair.truth, 16, [](const auto& v) { return v.x_px > 80; });
  ASSERT_GT(far_left.compared, 50u);
  ASSERT_GT(far_right.compared, 50u);
  EXPECT_LT(far_left.rms, 0.05);
  EXPECT_LT(far_right.rms, 0.05);
}

TEST(CrossCorrelation, RecoversASinusoid) {
  const auto truth = sim::DisplacementModel::sinusoid(1.0, 128);
  const auto pair = render(truth);
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
  const auto e = errors(result.field, pair.truth, 16);
  EXPECT_GT(e.compared, 0.95 * result.field.size());
  EXPECT_LT(e.rms, 0.05);
}

TEST(CrossCorrelation, RecoversTheGradientOfABump) {
  const auto truth = sim::DisplacementModel::bump_gradient(128, 128, 40, 1.5);
  const auto pair = render(truth);
  const auto e = errors(evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{}).field, pair.truth, 16);
  EXPECT_LT(e.rms, 0.05);
}

TEST(CrossCorrelation, MaskedWindowsAreFlaggedAndTheRestIsMeasured) {
  const auto pair = render(sim::DisplacementModel::uniform(0.6, 0.2));
  cv::Mat mask = cv::Mat::zeros(256, 256, CV_8U);
  const cv::Rect holder(96, 96, 64, 64);
  mask(holder).setTo(255);
  // Where the holder hides the background the two images differ entirely.
  cv::Mat measurement = pair.measurement.clone();
  measurement(holder).setTo(30);
  const auto result = evaluate_xcorr(pair.reference, measurement, XcorrOptions{}, mask);
  std::size_t masked_inside = 0;
  for (const auto& v : result.field.vectors) {
    if (holder.contains(cv::Point(int(v.x_px), int(v.y_px)))) {
      EXPECT_EQ(v.flag, VectorFlag::kMasked) << v.x_px << "," << v.y_px;
      EXPECT_EQ(v.u_px, 0.0);
      masked_inside += v.flag == VectorFlag::kMasked;
    }
  }
  EXPECT_GT(masked_inside, 40u);
  const auto e = errors(result.field, pair.truth, 16);
  EXPECT_GT(e.compared, 0.8 * result.field.size());
  EXPECT_LT(e.rms, 0.03);
}

TEST(CrossCorrelation, RoiLimitsTheGrid) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0.5));
  XcorrOptions options;
  options.roi = cv::Rect(32, 40, 64, 48);
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_EQ(result.field.cols, (64 - 16) / 8 + 1);
  EXPECT_EQ(result.field.rows, (48 - 16) / 8 + 1);
  for (const auto& v : result.field.vectors) {
    EXPECT_GE(v.x_px - 7.5, 32);
    EXPECT_LE(v.y_px + 7.5, 40 + 47);
  }
}

TEST(CrossCorrelation, ProbeWithFullContextEqualsTheFullField) {
  const auto pair = render(sim::DisplacementModel::sinusoid(1.2, 96), 384);
  XcorrOptions options;
  options.convergence_px = 0;  // the same number of passes for both
  const auto full = evaluate_xcorr(pair.reference, pair.measurement, options);
  std::vector<cv::Point2d> points;
  std::vector<const DisplacementVector*> expected;
  // Away from the edges by the exact context, so the probes' grids see the
  // same neighbourhood as the full field's.
  const int margin = options.exact_probe_context_nodes();
  for (int row = margin; row < full.field.rows - margin; row += 5) {
    for (int col = margin + 1; col < full.field.cols - margin; col += 4) {
      points.push_back({full.field.at(row, col).x_px, full.field.at(row, col).y_px});
      expected.push_back(&full.field.at(row, col));
    }
  }
  ASSERT_GE(points.size(), 4u);
  options.probe_context_nodes = -1;
  const auto exact = probe_xcorr(pair.reference, pair.measurement, points, options);
  options.probe_context_nodes = 1;
  const auto fast = probe_xcorr(pair.reference, pair.measurement, points, options);
  ASSERT_EQ(exact.field.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(exact.field.vectors[i].x_px, expected[i]->x_px);
    EXPECT_EQ(exact.field.vectors[i].flag, expected[i]->flag);
    EXPECT_NEAR(exact.field.vectors[i].u_px, expected[i]->u_px, 1e-9);
    EXPECT_NEAR(exact.field.vectors[i].v_px, expected[i]->v_px, 1e-9);
    // With one node of context the probe is an independent estimate of the
    // same quantity: within the measurement's own scatter of the full field.
    EXPECT_NEAR(fast.field.vectors[i].v_px, expected[i]->v_px, 0.15);
  }
}

TEST(CrossCorrelation, ProbeOutsideTheImageIsFlagged) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0.5), 64);
  const auto result = probe_xcorr(pair.reference, pair.measurement, {{2, 2}, {31.5, 31.5}, {500, 10}}, XcorrOptions{});
  ASSERT_EQ(result.field.size(), 3u);
  EXPECT_EQ(result.field.vectors[0].flag, VectorFlag::kOutOfRoi);
  EXPECT_EQ(result.field.vectors[1].flag, VectorFlag::kOk);
  EXPECT_NEAR(result.field.vectors[1].u_px, 0.5, 0.05);
  EXPECT_EQ(result.field.vectors[2].flag, VectorFlag::kOutOfRoi);
}

// Points at the ends of the int range (and beyond it) once overflowed the
// reach's pixel arithmetic (seen under UBSan); they are flagged like any
// probe outside the image.
TEST(CrossCorrelation, ProbesFarOutsideTheImageAreFlaggedWithoutOverflow) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0.5), 64);
  const std::vector<cv::Point2d> points = {{-2147483648.0, 0},   {2147483647.0, 10},   {2147483600.0, 10},
                                           {10, -2147483648.0},  {1e300, -1e300},      {NAN, 10},
                                           {31.5, 31.5}};
  for (int context : {-1, 0, 1}) {
    XcorrOptions options;
    options.probe_context_nodes = context;
    const auto result = probe_xcorr(pair.reference, pair.measurement, points, options);
    ASSERT_EQ(result.field.size(), points.size());
    for (std::size_t i = 0; i + 1 < points.size(); ++i) {
      EXPECT_EQ(result.field.vectors[i].flag, VectorFlag::kOutOfRoi) << "point " << i << ", context " << context;
    }
    EXPECT_EQ(result.field.vectors.back().flag, VectorFlag::kOk);
  }
}

TEST(CrossCorrelation, DirectAndFftCorrelationGiveTheSameField) {
  const auto pair = render(sim::DisplacementModel::bump_gradient(128, 128, 40, 2.0), 192);
  XcorrOptions options;
  options.correlation = CorrelationMethod::kDirect;
  const auto direct = evaluate_xcorr(pair.reference, pair.measurement, options);
  options.correlation = CorrelationMethod::kFft;
  const auto fft = evaluate_xcorr(pair.reference, pair.measurement, options);
  ASSERT_EQ(direct.field.size(), fft.field.size());
  for (std::size_t i = 0; i < direct.field.size(); ++i) {
    EXPECT_EQ(direct.field.vectors[i].flag, fft.field.vectors[i].flag);
    EXPECT_NEAR(direct.field.vectors[i].u_px, fft.field.vectors[i].u_px, 1e-3);
    EXPECT_NEAR(direct.field.vectors[i].v_px, fft.field.vectors[i].v_px, 1e-3);
  }
}

TEST(CrossCorrelation, ALargerFirstWindowFindsAShiftBeyondTheSmallSearch) {
  const auto pair = render(sim::DisplacementModel::uniform(5.4, -3.2));
  XcorrOptions options;
  options.first_window_px = 32;
  options.max_shift_px = 7;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  ASSERT_FALSE(result.summary.window_px_per_pass.empty());
  EXPECT_EQ(result.summary.window_px_per_pass.front(), 32);
  const auto e = errors(result.field, pair.truth, 16);
  EXPECT_GT(e.compared, 0.95 * result.field.size());
  EXPECT_LT(e.rms, 0.05);
}

TEST(CrossCorrelation, ACoarseFirstPassEndsWhereAFullOneDoes) {
  const auto pair = render(sim::DisplacementModel::bump_gradient(128, 128, 40, 2.0));
  XcorrOptions options;
  const auto coarse = evaluate_xcorr(pair.reference, pair.measurement, options);
  options.coarse_first_pass = false;
  const auto full = evaluate_xcorr(pair.reference, pair.measurement, options);
  ASSERT_EQ(coarse.field.size(), full.field.size());
  double sum_sq = 0;
  for (std::size_t i = 0; i < full.field.size(); ++i) {
    sum_sq += std::pow(coarse.field.vectors[i].u_px - full.field.vectors[i].u_px, 2) +
              std::pow(coarse.field.vectors[i].v_px - full.field.vectors[i].v_px, 2);
  }
  EXPECT_LT(std::sqrt(sum_sq / full.field.size()), 0.005);
  EXPECT_LT(errors(coarse.field, pair.truth, 16).rms, 0.05);
}

TEST(CrossCorrelation, SymmetricDeformationRecoversAGradient) {
  const auto pair = render(sim::DisplacementModel::bump_gradient(128, 128, 40, 2.0));
  XcorrOptions options;
  options.symmetric_deformation = true;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  const auto e = errors(result.field, pair.truth, 16);
  EXPECT_GT(e.compared, 0.95 * result.field.size());
  EXPECT_LT(e.rms, 0.05);
  EXPECT_LT(std::abs(e.mean_u), 0.01);
}

TEST(CrossCorrelation, ShiftsBeyondAnExplicitSearchAreFlaggedBeyondSearch) {
  const auto pair = render(sim::DisplacementModel::uniform(6.0, 0.0), 128);
  XcorrOptions options;
  options.max_shift_px = 2;
  options.find_search_range = false;
  options.passes = 1;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_GT(result.field.count(VectorFlag::kBeyondSearch), result.field.size() / 2);
  // One pass of 16 px windows, three times the bound: the few noise peaks as
  // clear as a measurement's among windows that measured are all that is left.
  EXPECT_LE(result.field.count_valid(), result.field.size() / 50);
  EXPECT_TRUE(all_finite(result.field));
}

TEST(CrossCorrelation, OutliersAreReplacedAndFlagged) {
  const auto pair = render(sim::DisplacementModel::uniform(0.4, 0.4), 128, 0.01);
  // Scramble one window of the measurement: its vector becomes noise.
  cv::Mat measurement = pair.measurement.clone();
  cv::Mat patch = measurement(cv::Rect(56, 56, 16, 16));
  cv::randu(patch, 0, 255);
  XcorrOptions options;
  options.passes = 1;
  options.max_shift_px = 6;
  const auto result = evaluate_xcorr(pair.reference, measurement, options);
  const auto& centre = result.field.at(7, 7);  // the window at (56..71, 56..71)
  ASSERT_EQ(centre.x_px, 63.5);
  // Its peak is noise: not told from it (no peak, or on the bound), or
  // replaced by its neighbours' median; never a valid wrong vector.
  const bool not_measured = centre.flag == VectorFlag::kNoPeak || centre.flag == VectorFlag::kBeyondSearch;
  EXPECT_TRUE(centre.flag == VectorFlag::kOutlierReplaced || centre.flag == VectorFlag::kOk || not_measured);
  if (!not_measured) EXPECT_NEAR(centre.u_px, 0.4, 0.1) << to_string(centre.flag);
  EXPECT_GE(result.summary.outliers_replaced + result.field.count(VectorFlag::kNoPeak) +
                result.field.count(VectorFlag::kBeyondSearch),
            1u);
}

TEST(CrossCorrelation, RefinementStopsWhenAPassChangesNothing) {
  const auto pair = render(sim::DisplacementModel::uniform(0.25, 0.25), 128, 0.0);
  XcorrOptions options;
  options.passes = 10;
  options.convergence_px = 0.01;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_TRUE(result.summary.converged);
  EXPECT_LT(result.summary.passes_run, 10);
}

// Adaptive refinement: a bump in the middle of a 384 px frame, displaced
// over about a fifth of it.
class AdaptiveRefinementScene : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    pair_ = new sim::SyntheticPair(render(sim::DisplacementModel::bump_gradient(192, 192, 30, 1.5), 384));
  }
  static void TearDownTestSuite() {
    delete pair_;
    pair_ = nullptr;
  }
  static EvaluationResult evaluate(bool adaptive, double threshold = 4, double smoothing_nodes = 2) {
    XcorrOptions options;
    options.adaptive_refinement = adaptive;
    options.adaptive_threshold = threshold;
    options.adaptive_smoothing_nodes = smoothing_nodes;
    return evaluate_xcorr(pair_->reference, pair_->measurement, options);
  }
  static sim::SyntheticPair* pair_;
};
sim::SyntheticPair* AdaptiveRefinementScene::pair_ = nullptr;

TEST_F(AdaptiveRefinementScene, RefinesTheDisplacedRegionAsFullRefinementDoes) {
  const auto full = evaluate(false);
  const auto adaptive = evaluate(true);
  EXPECT_DOUBLE_EQ(full.summary.refined_fraction, 1.0);
  EXPECT_GT(adaptive.summary.refined_fraction, 0.1);
  EXPECT_LT(adaptive.summary.refined_fraction, 0.5);
  ASSERT_EQ(adaptive.field.size(), full.field.size());
  double sum_sq = 0, largest = 0;
  std::size_t refined = 0;
  for (std::size_t i = 0; i < full.field.size(); ++i) {
    const auto& a = adaptive.field.vectors[i];
    if (a.first_pass_only) continue;
    const double d = std::hypot(a.u_px - full.field.vectors[i].u_px, a.v_px - full.field.vectors[i].v_px);
    sum_sq += d * d;
    largest = std::max(largest, d);
    ++refined;
  }
  ASSERT_GT(refined, 0u);
  EXPECT_EQ(double(refined) / full.field.size(), adaptive.summary.refined_fraction);
  EXPECT_LT(std::sqrt(sum_sq / refined), 0.002);
  EXPECT_LT(largest, 0.02);
  // Every clearly displaced window is among the refined ones.
  for (const auto& vec : adaptive.field.vectors) {
    const cv::Point2d d = pair_->truth.at(vec.x_px, vec.y_px);
    if (std::hypot(d.x, d.y) > 0.2) {
      EXPECT_FALSE(vec.first_pass_only) << vec.x_px << "," << vec.y_px;
    }
  }
  // Where it refines, as accurate as full refinement; elsewhere (the
  // smoothed first pass) about as accurate too.
  std::vector<bool> refined_here(full.field.size());
  for (std::size_t i = 0; i < full.field.size(); ++i) refined_here[i] = !adaptive.field.vectors[i].first_pass_only;
  auto in_refined = [&](const DisplacementField& field) {
    return [&](const DisplacementVector& v) {
      return refined_here[static_cast<std::size_t>(&v - field.vectors.data())];
    };
  };
  EXPECT_LT(errors(adaptive.field, pair_->truth, 16, in_refined(adaptive.field)).rms,
            1.02 * errors(full.field, pair_->truth, 16, in_refined(full.field)).rms);
  EXPECT_LT(errors(adaptive.field, pair_->truth, 16).rms, 1.05 * errors(full.field, pair_->truth, 16).rms);
  EXPECT_NE(adaptive.summary.BriefReport().find("% refined"), std::string::npos);
}

TEST_F(AdaptiveRefinementScene, KeepsTheSmoothedFirstPassElsewhere) {
  // A threshold nothing reaches, no smoothing: every node keeps the first pass's value.
  const auto first_pass = evaluate(true, 1e9, 0);
  EXPECT_LT(first_pass.summary.refined_fraction, 0.02);
  const auto adaptive = evaluate(true);
  cv::Mat refine(adaptive.field.rows, adaptive.field.cols, CV_8U);
  for (std::size_t i = 0; i < adaptive.field.size(); ++i) refine.data[i] = !adaptive.field.vectors[i].first_pass_only;
  DisplacementField expected = first_pass.field;
  smooth_unrefined(expected, refine, 2);
  std::size_t kept = 0;
  for (std::size_t i = 0; i < adaptive.field.size(); ++i) {
    const auto& a = adaptive.field.vectors[i];
    if (!a.first_pass_only) continue;
    ASSERT_TRUE(first_pass.field.vectors[i].first_pass_only);
    EXPECT_NEAR(a.u_px, expected.vectors[i].u_px, 1e-12);
    EXPECT_NEAR(a.v_px, expected.vectors[i].v_px, 1e-12);
    EXPECT_EQ(a.flag, VectorFlag::kOk);
    ++kept;
  }
  EXPECT_GT(kept, adaptive.field.size() / 2);
  // There the first pass alone is unbiased but noisier than refinement; smoothed, it is not.
  auto kept_only = [](const auto& v) { return v.first_pass_only; };
  const auto raw = errors(first_pass.field, pair_->truth, 16, [&](const auto& v) {
    return adaptive.field.vectors[static_cast<std::size_t>(&v - first_pass.field.vectors.data())].first_pass_only;
  });
  const auto smoothed = errors(adaptive.field, pair_->truth, 16, kept_only);
  EXPECT_LT(std::abs(raw.mean_u) + std::abs(raw.mean_v), 0.005);
  EXPECT_LT(smoothed.rms, 0.6 * raw.rms);
  EXPECT_LT(std::abs(smoothed.mean_u) + std::abs(smoothed.mean_v), 0.005);
}

TEST_F(AdaptiveRefinementScene, SelectingEverythingIsBitIdenticalToFullRefinement) {
  // The hooks (evaluating selected nodes, warping selected tiles) change no
  // value: a threshold every displacement exceeds gives the full field.
  const auto full = evaluate(false);
  const auto everything = evaluate(true, 1e-12);
  ASSERT_DOUBLE_EQ(everything.summary.refined_fraction, 1.0);
  for (std::size_t i = 0; i < full.field.size(); ++i) {
    const auto &a = everything.field.vectors[i], &b = full.field.vectors[i];
    ASSERT_EQ(a.u_px, b.u_px) << i;
    ASSERT_EQ(a.v_px, b.v_px) << i;
    ASSERT_EQ(a.peak_ratio, b.peak_ratio) << i;
    ASSERT_EQ(a.flag, b.flag) << i;
    ASSERT_FALSE(b.first_pass_only);
  }
  EXPECT_EQ(everything.summary.passes_run, full.summary.passes_run);
}

TEST(CrossCorrelation, AdaptiveRefinementOfAStillSceneRefinesAlmostNothing) {
  const auto pair = render(sim::DisplacementModel::uniform(0, 0), 256);
  XcorrOptions options;
  options.adaptive_refinement = true;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_LT(result.summary.refined_fraction, 0.1);
  EXPECT_LT(errors(result.field, pair.truth, 16).rms, 0.01);
  EXPECT_TRUE(all_finite(result.field));
}

TEST(CrossCorrelation, AdaptiveRefinementKeepsMaskedWindowsMasked) {
  const auto pair = render(sim::DisplacementModel::uniform(0, 0), 256);
  cv::Mat mask(256, 256, CV_8U, cv::Scalar(0));
  mask(cv::Rect(100, 100, 60, 60)).setTo(255);
  XcorrOptions options;
  const auto full = evaluate_xcorr(pair.reference, pair.measurement, options, mask);
  options.adaptive_refinement = true;
  const auto adaptive = evaluate_xcorr(pair.reference, pair.measurement, options, mask);
  EXPECT_EQ(adaptive.summary.masked, full.summary.masked);
  for (std::size_t i = 0; i < full.field.size(); ++i) {
    EXPECT_EQ(adaptive.field.vectors[i].flag == VectorFlag::kMasked, full.field.vectors[i].flag == VectorFlag::kMasked)
        << i;
  }
}

TEST(CrossCorrelation, ProbesIgnoreAdaptiveRefinement) {
  const auto pair = render(sim::DisplacementModel::uniform(0.3, -0.2), 192);
  XcorrOptions options;
  const std::vector<cv::Point2d> points{{96, 96}};
  const auto plain = probe_xcorr(pair.reference, pair.measurement, points, options);
  options.adaptive_refinement = true;
  const auto adaptive = probe_xcorr(pair.reference, pair.measurement, points, options);
  EXPECT_EQ(adaptive.field.vectors[0].u_px, plain.field.vectors[0].u_px);
  EXPECT_FALSE(adaptive.field.vectors[0].first_pass_only);
}

// Numerical edge cases: flagged vectors, never NaN or a crash.

TEST(CrossCorrelationEdges, ConstantImagesGiveNoTextureVectors) {
  const cv::Mat flat(64, 64, CV_8U, cv::Scalar(128));
  const auto result = evaluate_xcorr(flat, flat, XcorrOptions{});
  EXPECT_EQ(result.field.count(VectorFlag::kNoTexture), result.field.size());
  EXPECT_TRUE(all_finite(result.field));
}

// 6 px dots give a correlation peak broader than 3×3; its flank is not a
// second peak, so the first pass does not refuse the windows as no-peak
// (it refused 80 % of them at 50 % coverage), and what it keeps is right.
TEST(CrossCorrelationFlags, LargeDotsAreMeasuredNotRefusedAsNoPeak) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 256;
  options.pattern.dot_diameter_px = 6;
  options.pattern.coverage = 0.5;
  options.pattern.seed = 5;
  options.noise_std = 0.01;
  options.field = sim::DisplacementModel::uniform(0.3, -0.2);
  const auto pair = sim::render_pair(options);
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
  EXPECT_GE(result.field.count_valid(), 0.95 * double(result.field.size()));
  EXPECT_EQ(result.field.count(VectorFlag::kNoPeak), 0u);
  const auto interior = [&](const DisplacementVector& v) {
    return v.x_px >= 16 && v.y_px >= 16 && v.x_px <= 240 && v.y_px <= 240;
  };
  const ErrorStats e = errors(result.field, options.field, 16, interior);
  ASSERT_GT(e.compared, 500u);
  EXPECT_LT(e.rms, 0.03);
  EXPECT_LT(std::abs(e.mean_u), 0.005);
  EXPECT_LT(std::abs(e.mean_v), 0.005);
  for (const auto& v : result.field.vectors) {
    if (v.valid() && interior(v)) {
      EXPECT_LT(std::hypot(v.u_px - 0.3, v.v_px + 0.2), 0.15) << v.x_px << "," << v.y_px;
    }
  }
}

TEST(CrossCorrelationEdges, FlatMeasurementGivesNoPeak) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 64);
  const cv::Mat flat(64, 64, CV_8U, cv::Scalar(255));  // saturated
  const auto result = evaluate_xcorr(pair.reference, flat, XcorrOptions{});
  EXPECT_EQ(result.field.count(VectorFlag::kNoPeak), result.field.size());
  EXPECT_TRUE(all_finite(result.field));
}

TEST(CrossCorrelationEdges, PartlySaturatedImagesStillMeasure) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0.25), 128);
  cv::Mat ref, meas;
  // Over-exposure: the white background and the edges of dots clip at 255.
  pair.reference.convertTo(ref, CV_8U, 1.25);
  pair.measurement.convertTo(meas, CV_8U, 1.25);
  const auto result = evaluate_xcorr(ref, meas, XcorrOptions{});
  EXPECT_TRUE(all_finite(result.field));
  EXPECT_LT(errors(result.field, pair.truth, 16).rms, 0.08);
}

TEST(CrossCorrelationEdges, SixteenBitFullScaleImagesMeasureLikeEightBit) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 128;
  options.bit_depth = 16;
  options.field = sim::DisplacementModel::uniform(0.3, 0.6);
  const auto pair = sim::render_pair(options);
  ASSERT_EQ(pair.reference.depth(), CV_16U);
  double max_value = 0;
  cv::minMaxLoc(pair.reference, nullptr, &max_value);
  EXPECT_GT(max_value, 60000);
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
  EXPECT_TRUE(all_finite(result.field));
  EXPECT_LT(errors(result.field, pair.truth, 16).rms, 0.03);
  const cv::Mat full(64, 64, CV_16U, cv::Scalar(65535));
  EXPECT_EQ(evaluate_xcorr(full, full, XcorrOptions{}).field.count(VectorFlag::kNoTexture), 49u);
}

TEST(CrossCorrelationEdges, TinyImages) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 8, 0.0);
  XcorrOptions options;
  options.window_px = 8;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  ASSERT_EQ(result.field.size(), 1u);
  EXPECT_TRUE(all_finite(result.field));
  EXPECT_THROW(evaluate_xcorr(pair.reference(cv::Rect(0, 0, 6, 6)), pair.measurement(cv::Rect(0, 0, 6, 6)), options),
               std::invalid_argument);
}

TEST(CrossCorrelationEdges, AllMaskedImageGivesOnlyMaskedVectors) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 64);
  const cv::Mat mask(64, 64, CV_8U, cv::Scalar(1));
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{}, mask);
  EXPECT_EQ(result.field.count(VectorFlag::kMasked), result.field.size());
  EXPECT_TRUE(all_finite(result.field));
}

TEST(CrossCorrelationEdges, NanPixelsInFloatImagesDoNotLeak) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 64);
  cv::Mat ref, meas;
  pair.reference.convertTo(ref, CV_32F, 1 / 255.0);
  pair.measurement.convertTo(meas, CV_32F, 1 / 255.0);
  ref.at<float>(20, 20) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(all_finite(evaluate_xcorr(ref, meas, XcorrOptions{}).field));
}

// Bad input: a message that names the problem.

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

TEST(CrossCorrelationInput, ProblemsAreNamed) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 64);
  const cv::Mat smaller = pair.measurement(cv::Rect(0, 0, 48, 64)).clone();
  EXPECT_NE(message_of([&] { evaluate_xcorr(pair.reference, smaller, {}); }).find("sizes differ"), std::string::npos);
  EXPECT_NE(message_of([&] { evaluate_xcorr(cv::Mat(), pair.measurement, {}); }).find("reference image is empty"),
            std::string::npos);
  XcorrOptions big;
  big.window_px = 128;
  EXPECT_NE(message_of([&] { evaluate_xcorr(pair.reference, pair.measurement, big); }).find("larger than the image"),
            std::string::npos);
  XcorrOptions odd;
  odd.window_px = 4;
  EXPECT_NE(message_of([&] { evaluate_xcorr(pair.reference, pair.measurement, odd); }).find("8 to 128"),
            std::string::npos);
  XcorrOptions no_threshold;
  no_threshold.adaptive_threshold = 0;
  EXPECT_NE(message_of([&] { evaluate_xcorr(pair.reference, pair.measurement, no_threshold); })
                .find("adaptive refinement threshold"),
            std::string::npos);
  const cv::Mat wrong_mask(10, 10, CV_8U, cv::Scalar(0));
  EXPECT_NE(message_of([&] { evaluate_xcorr(pair.reference, pair.measurement, {}, wrong_mask); }).find("mask size"),
            std::string::npos);
}

TEST(CrossCorrelationInput, ColourImagesAreConvertedWithAWarning) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0.25), 96);
  cv::Mat ref_bgr, meas_bgr;
  cv::cvtColor(pair.reference, ref_bgr, cv::COLOR_GRAY2BGR);
  cv::cvtColor(pair.measurement, meas_bgr, cv::COLOR_GRAY2BGR);
  const auto colour = evaluate_xcorr(ref_bgr, meas_bgr, XcorrOptions{});
  std::string warnings;  // what the caller logs
  for (const auto& warning : colour.summary.warnings) warnings += warning + "\n";
  EXPECT_NE(warnings.find("colour image"), std::string::npos) << warnings;
  const auto grey = evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
  ASSERT_EQ(colour.field.size(), grey.field.size());
  for (std::size_t i = 0; i < grey.field.size(); ++i) {
    EXPECT_NEAR(colour.field.vectors[i].u_px, grey.field.vectors[i].u_px, 1e-6);
  }
}

// An evaluator keeps the reference's window statistics and the frame's
// buffers (float image, warped images, correlator scratch) between frames;
// none of that may carry one frame's content into the next. Each node's
// vector is computed from the same numbers in the same order whichever
// buffer holds them and whichever thread runs it, so the fields are equal
// exactly, not just to rounding.
void expect_same_fields(const EvaluationResult& a, const EvaluationResult& b) {
  ASSERT_EQ(a.field.size(), b.field.size());
  for (std::size_t i = 0; i < a.field.size(); ++i) {
    ASSERT_EQ(a.field.vectors[i].x_px, b.field.vectors[i].x_px) << i;
    ASSERT_EQ(a.field.vectors[i].flag, b.field.vectors[i].flag) << i;
    ASSERT_EQ(a.field.vectors[i].u_px, b.field.vectors[i].u_px) << i;
    ASSERT_EQ(a.field.vectors[i].v_px, b.field.vectors[i].v_px) << i;
    ASSERT_EQ(a.field.vectors[i].peak_ratio, b.field.vectors[i].peak_ratio) << i;
  }
  EXPECT_EQ(a.summary.passes_run, b.summary.passes_run);
  EXPECT_EQ(a.summary.outliers_replaced, b.summary.outliers_replaced);
}

TEST(XcorrEvaluator, FramesAfterTheFirstEqualFreshEvaluations) {
  const auto first = render(sim::DisplacementModel::sinusoid(1.2, 96), 256, 0.01, 5);
  const std::vector<cv::Mat> frames = {
      first.measurement, render(sim::DisplacementModel::bump_gradient(80, 80, 24, 1.5), 256, 0.01, 5).measurement,
      render(sim::DisplacementModel::uniform(-0.7, 0.4), 256, 0.02, 5).measurement};
  cv::Mat mask(first.reference.size(), CV_8U, cv::Scalar(0));
  cv::circle(mask, {60, 190}, 25, cv::Scalar(255), cv::FILLED);
  XcorrOptions coarse_to_fine;  // two window sizes, a coarse first pass and FFT in it
  coarse_to_fine.first_window_px = 32;
  coarse_to_fine.max_shift_px = 6;
  XcorrOptions symmetric;  // the reference warped too: its statistics cannot be kept
  symmetric.symmetric_deformation = true;
  XcorrOptions adaptive;  // the bump is refined in tiles of a buffer an earlier frame warped whole
  adaptive.adaptive_refinement = true;
  for (const XcorrOptions& options : {XcorrOptions{}, coarse_to_fine, symmetric, adaptive}) {
    XcorrEvaluator evaluator(first.reference, options, mask);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      SCOPED_TRACE(testing::Message() << "frame " << i << ", first window " << options.first_window_px);
      const auto reused = evaluator.evaluate(frames[i]);
      const auto fresh = XcorrEvaluator(first.reference, options, mask).evaluate(frames[i]);
      expect_same_fields(reused, fresh);
      expect_same_fields(reused, evaluate_xcorr(first.reference, frames[i], options, mask));
      EXPECT_GT(reused.summary.valid, reused.field.size() / 2);
      EXPECT_GT(reused.summary.masked, 0u);
      if (options.adaptive_refinement && i == 1) {
        EXPECT_LT(reused.summary.refined_fraction, 0.9) << "refined in part";
      }
      const std::vector<cv::Point2d> points = {{100.5, 60.5}, {180, 200}};
      expect_same_fields(evaluator.probe(frames[i], points),
                         probe_xcorr(first.reference, frames[i], points, options, mask));
    }
  }
}

TEST(XcorrEvaluator, ProblemsAreNamedWhereTheyArise) {
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0), 64);
  EXPECT_NE(message_of([&] { XcorrEvaluator(cv::Mat(), XcorrOptions{}); }).find("reference image is empty"),
            std::string::npos);
  XcorrEvaluator evaluator(pair.reference, XcorrOptions{});
  const cv::Mat smaller = pair.measurement(cv::Rect(0, 0, 48, 64)).clone();
  EXPECT_NE(message_of([&] { evaluator.evaluate(smaller); }).find("sizes differ"), std::string::npos);
  EXPECT_NE(message_of([&] { evaluator.probe(cv::Mat(), {{31.5, 31.5}}); }).find("measurement image is empty"),
            std::string::npos);
  // A bad frame leaves the evaluator usable.
  EXPECT_EQ(evaluator.evaluate(pair.measurement).summary.valid,
            evaluate_xcorr(pair.reference, pair.measurement, {}).summary.valid);
}

}  // namespace
}  // namespace bosfuse::fusion
