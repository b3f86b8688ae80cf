#include "fusion/search_range.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "fusion/cross_correlation.h"
#include "fusion/image_input.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

// The 768×768 dot pattern of the cases (3 px dots, half covered,
// 1 % noise), shifted uniformly by (u, v).
sim::SyntheticPair shifted_pair(double u_px, double v_px, int size_px = 768) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = size_px;
  options.pattern.dot_diameter_px = 3;
  options.pattern.coverage = 0.5;
  options.pattern.seed = 11;
  options.noise_std = 0.01;
  options.field = sim::DisplacementModel::uniform(u_px, v_px);
  return sim::render_pair(options);
}

struct SearchAccuracy {
  double rms_px = 0;
  double interior_valid_fraction = 0;
  double worst_valid_error_px = 0;  // the largest error of any valid vector
  std::size_t valid = 0;
};

// Interior: more than one (final) window from the image's border.
SearchAccuracy accuracy(const DisplacementField& field, double u_px, double v_px, int size_px, int window_px = 16) {
  SearchAccuracy a;
  double sum_sq = 0;
  std::size_t interior = 0, interior_valid = 0;
  for (const auto& vec : field.vectors) {
    const bool inside = vec.x_px > 1.5 * window_px && vec.y_px > 1.5 * window_px &&
                        vec.x_px < size_px - 1.5 * window_px && vec.y_px < size_px - 1.5 * window_px;
    if (inside) ++interior;
    if (!vec.valid()) continue;
    const double e2 = std::pow(vec.u_px - u_px, 2) + std::pow(vec.v_px - v_px, 2);
    a.worst_valid_error_px = std::max(a.worst_valid_error_px, std::sqrt(e2));
    sum_sq += e2;
    ++a.valid;
    if (inside) ++interior_valid;
  }
  a.rms_px = a.valid ? std::sqrt(sum_sq / a.valid) : 0;
  a.interior_valid_fraction = interior ? double(interior_valid) / interior : 0;
  return a;
}

EvaluationResult evaluate_defaults(const sim::SyntheticPair& pair) {
  return evaluate_xcorr(pair.reference, pair.measurement, XcorrOptions{});
}

// The sample alone, on the images as the evaluator converts them.
SearchRange search_of(const sim::SyntheticPair& pair) {
  const cv::Mat reference = to_grey_unit_float(pair.reference, "reference");
  const cv::Mat measurement = to_grey_unit_float(pair.measurement, "measurement");
  return find_search_range(reference, measurement, cv::Rect({0, 0}, reference.size()), {}, SearchStart{},
                           SearchRangeOptions{});
}

TEST(SearchRange, ScenesWithinTheDefaultBoundKeepItAndStayAccurate) {
  for (const double u : {0.0, 2.0}) {
    const auto pair = shifted_pair(u, 0);
    const SearchRange range = search_of(pair);
    EXPECT_FALSE(range.widened) << u << ": " << range.Describe();
    EXPECT_EQ(range.max_shift_px, 4);
    EXPECT_GT(range.sampled, 48);
    const auto result = evaluate_defaults(pair);
    EXPECT_TRUE(result.summary.search_from_scene);
    EXPECT_FALSE(result.summary.search_widened);
    EXPECT_EQ(result.summary.window_px_per_pass.front(), 16) << "no wider first window than needed";
    const SearchAccuracy a = accuracy(result.field, u, 0, 768);
    EXPECT_LE(a.rms_px, 0.03) << u;
    EXPECT_GE(a.interior_valid_fraction, 0.99) << u;
    EXPECT_TRUE(search_bound_warning(result.summary).empty()) << search_bound_warning(result.summary);
  }
}

// The pair: |d| = 6.5 px, where the default ±4 px search saw noise.
TEST(SearchRange, ASixAndAHalfPixelShiftIsFoundWithDefaultOptions) {
  const auto pair = shifted_pair(5.3, -3.7);
  const auto result = evaluate_defaults(pair);
  EXPECT_TRUE(result.summary.search_widened) << result.summary.BriefReport();
  EXPECT_GE(result.summary.max_shift_px, 6);
  const SearchAccuracy a = accuracy(result.field, 5.3, -3.7, 768);
  EXPECT_LE(a.rms_px, 0.03) << result.summary.BriefReport();
  EXPECT_GE(a.interior_valid_fraction, 0.99) << result.summary.BriefReport();
  EXPECT_LE(a.worst_valid_error_px, 0.5);
}

TEST(SearchRange, AFourteenPixelShiftIsFoundWithDefaultOptions) {
  const auto pair = shifted_pair(14, 0);
  const auto result = evaluate_defaults(pair);
  EXPECT_TRUE(result.summary.search_widened) << result.summary.BriefReport();
  EXPECT_GE(result.summary.max_shift_px, 14.5);
  EXPECT_GE(result.summary.first_window_px, 56);
  const SearchAccuracy a = accuracy(result.field, 14, 0, 768);
  EXPECT_LE(a.rms_px, 0.03) << result.summary.BriefReport();
  EXPECT_GE(a.interior_valid_fraction, 0.99) << result.summary.BriefReport();
  EXPECT_LE(a.worst_valid_error_px, 0.5);
}

TEST(SearchRange, AFortyPixelShiftIsReportedAndNoWrongVectorIsValid) {
  const auto pair = shifted_pair(32, -24);
  const auto result = evaluate_defaults(pair);
  EXPECT_TRUE(result.summary.search_beyond_reach) << result.summary.BriefReport();
  const std::string warning = search_bound_warning(result.summary);
  EXPECT_NE(warning.find("exceed"), std::string::npos) << warning;
  const SearchAccuracy a = accuracy(result.field, 32, -24, 768);
  EXPECT_LE(a.worst_valid_error_px, 0.5) << a.valid << " valid; " << result.summary.BriefReport();
  EXPECT_GT(result.field.count(VectorFlag::kBeyondSearch), result.field.size() / 2);
}

TEST(SearchRange, AnExplicitBoundIsKeptAndItsPeaksOnTheBoundAreNeverValid) {
  const auto pair = shifted_pair(5.3, -3.7);
  XcorrOptions options;
  options.find_search_range = false;
  options.max_shift_px = 4;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_FALSE(result.summary.search_from_scene);
  EXPECT_EQ(result.summary.max_shift_px, 4);
  const SearchAccuracy a = accuracy(result.field, 5.3, -3.7, 768);
  EXPECT_LE(a.worst_valid_error_px, 0.5) << a.valid << " valid; " << result.summary.BriefReport();
  EXPECT_GT(result.summary.on_bound_fraction(), kOnBoundWarningFraction);
  const std::string warning = search_bound_warning(result.summary);
  EXPECT_NE(warning.find("±4 px search bound"), std::string::npos) << warning;
  EXPECT_NE(warning.find("--max-shift"), std::string::npos) << warning;
}

// Half a pixel inside the bound is the bound: 3.8 px against ±4 px.
TEST(SearchRange, APeakWithinHalfAPixelOfTheBoundIsBeyondSearch) {
  const auto pair = shifted_pair(3.8, 0, 256);
  XcorrOptions options;
  options.find_search_range = false;
  options.passes = 1;
  const auto result = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_EQ(result.field.count_valid(), 0u) << result.summary.BriefReport();
  EXPECT_GT(result.field.count(VectorFlag::kBeyondSearch), result.field.size() * 9 / 10);
  options.max_shift_px = 5;  // the same shift well inside a wider bound
  const auto inside = evaluate_xcorr(pair.reference, pair.measurement, options);
  EXPECT_GT(inside.field.count_valid(), inside.field.size() * 9 / 10);
}

TEST(SearchRange, LaterFramesReuseWhatTheFirstFound) {
  const auto pair = shifted_pair(5.3, -3.7, 384);
  XcorrEvaluator evaluator(pair.reference, XcorrOptions{});
  const auto first = evaluator.evaluate(pair.measurement);
  ASSERT_TRUE(first.summary.search_widened);
  // A still frame next: the bound found at the first frame holds.
  const auto still = evaluator.evaluate(pair.reference);
  EXPECT_EQ(still.summary.max_shift_px, first.summary.max_shift_px);
  EXPECT_EQ(still.summary.first_window_px, first.summary.first_window_px);
}

TEST(SearchRangeOptions, ProblemsAreNamed) {
  SearchRangeOptions options;
  EXPECT_EQ(options.Validate(), "");
  options.sample_windows = 0;
  EXPECT_NE(options.Validate().find("sample"), std::string::npos);
  options = {};
  options.min_peak_ratio = 0.5;
  EXPECT_NE(options.Validate().find("ratio"), std::string::npos);
  options = {};
  options.widen_fraction = 2;
  EXPECT_NE(options.Validate().find("fraction"), std::string::npos);
}

}  // namespace
}  // namespace bosfuse::fusion
