#include "fusion/adaptive_refinement.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fusion/evaluation.h"

namespace bosfuse::fusion {
namespace {

GridGeometry grid_of(int rows, int cols, double step_px = 8, double x0_px = 7.5, double y0_px = 7.5) {
  return {x0_px, y0_px, step_px, rows, cols};
}

// A field on `grid` with value f(x, y) plus Gaussian noise of `noise_px` per component.
DisplacementField field_on(const GridGeometry& grid, const std::function<cv::Point2d(double, double)>& f,
                           double noise_px, std::uint64_t seed = 1) {
  cv::RNG rng(seed);
  DisplacementField field = field_on_grid(grid);
  for (auto& v : field.vectors) {
    const cv::Point2d d = f(v.x_px, v.y_px);
    v.u_px = d.x + rng.gaussian(noise_px);
    v.v_px = d.y + rng.gaussian(noise_px);
  }
  return field;
}

cv::Point2d zero(double, double) { return {0, 0}; }

// The gradient of a Gaussian bump centred at (cx, cy), peaking at `peak_px` at distance `radius_px`.
std::function<cv::Point2d(double, double)> bump(double cx, double cy, double radius_px, double peak_px) {
  return [=](double x, double y) {
    const double dx = x - cx, dy = y - cy;
    const double s = peak_px / radius_px * std::exp(0.5 - (dx * dx + dy * dy) / (2 * radius_px * radius_px));
    return cv::Point2d(s * dx, s * dy);
  };
}

TEST(AdaptiveRefinement, NoiseFloorIsTheVectorsScatter) {
  const auto grid = grid_of(60, 60);
  for (const double noise : {0.005, 0.02, 0.1}) {
    const double floor_px = field_noise_floor_px(field_on(grid, zero, noise));
    EXPECT_GT(floor_px, 0.95 * noise) << noise;
    EXPECT_LT(floor_px, 1.35 * noise) << noise;
  }
}

TEST(AdaptiveRefinement, NoiseFloorIgnoresASmoothDisplacement) {
  // A bump over much of the grid: against the neighbours' median only the noise is left.
  const auto grid = grid_of(60, 60);
  const double quiet = field_noise_floor_px(field_on(grid, zero, 0.02));
  const double with_bump = field_noise_floor_px(field_on(grid, bump(240, 240, 120, 1.5), 0.02));
  EXPECT_NEAR(with_bump, quiet, 0.15 * quiet);
}

TEST(AdaptiveRefinement, NoiseFloorIgnoresOutliers) {
  const auto grid = grid_of(40, 40);
  auto field = field_on(grid, zero, 0.02);
  for (std::size_t i = 0; i < field.size(); i += 20) field.vectors[i].u_px = 3.0;  // 5 % wild vectors
  EXPECT_LT(field_noise_floor_px(field), 1.5 * 0.02);
}

TEST(AdaptiveRefinement, TooFewVectorsSelectEverything) {
  const auto grid = grid_of(2, 2);
  const auto field = field_on(grid, zero, 0.01);
  EXPECT_EQ(field_noise_floor_px(field), -1);
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  EXPECT_EQ(selection.selected, 4u);
  EXPECT_DOUBLE_EQ(selection.fraction(), 1.0);
}

TEST(AdaptiveRefinement, PureNoiseSelectsAlmostNothing) {
  const auto grid = grid_of(100, 100);
  const auto field = field_on(grid, zero, 0.02, 5);
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  EXPECT_GT(selection.noise_floor_px, 0.015);
  EXPECT_LT(selection.fraction(), 0.005);
  EXPECT_EQ(selection.candidates, 10000u);
}

TEST(AdaptiveRefinement, ABumpSelectsItsRegion) {
  const auto grid = grid_of(80, 80);  // 640 px
  const auto bump_field = bump(320, 320, 60, 1.5);
  const auto field = field_on(grid, bump_field, 0.02);
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  const double threshold = selection.threshold_px;
  ASSERT_GT(threshold, 0);
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const auto& v = field.at(r, c);
      const cv::Point2d d = bump_field(v.x_px, v.y_px);
      const bool selected = selection.refine.at<std::uint8_t>(r, c);
      // Clearly displaced: selected; far below the threshold and away from the bump: not.
      if (std::hypot(d.x, d.y) > 2 * threshold) {
        EXPECT_TRUE(selected) << r << "," << c;
      }
      if (std::hypot(v.x_px - 320, v.y_px - 320) > 300) {
        EXPECT_FALSE(selected) << r << "," << c;
      }
    }
  }
  // The centre, where the displacement is 0 but its gradient largest, is selected.
  EXPECT_TRUE(selection.refine.at<std::uint8_t>(39, 39));
  EXPECT_GT(selection.fraction(), 0.05);
  EXPECT_LT(selection.fraction(), 0.5);
}

TEST(AdaptiveRefinement, AStepSelectsItsEdgeAndItsDisplacedSide) {
  const auto grid = grid_of(30, 60);
  const double step_x = 240;
  const auto field = field_on(
      grid, [&](double x, double) { return cv::Point2d(x >= step_x ? 1.0 : 0.0, 0); }, 0.02);
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double x = field.at(r, c).x_px;
      const bool selected = selection.refine.at<std::uint8_t>(r, c);
      if (x >= step_x) {
        EXPECT_TRUE(selected) << r << "," << c;
      }
      // The last node before the step: no displacement, but the gradient of the edge.
      if (x < step_x && x > step_x - grid.step_px) {
        EXPECT_TRUE(selected) << r << "," << c;
      }
      if (x < step_x - 3 * grid.step_px) {
        EXPECT_FALSE(selected) << r << "," << c;
      }
    }
  }
}

TEST(AdaptiveRefinement, AGradientThroughZeroIsSelected) {
  // u = 0.05 px per node across x = 240: near there |u| is below the threshold, the gradient is not.
  const auto grid = grid_of(30, 60);
  const auto field = field_on(
      grid, [](double x, double) { return cv::Point2d(0.05 * (x - 240) / 8, 0); }, 0.005);
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  ASSERT_LT(selection.threshold_px, 0.05);
  EXPECT_EQ(selection.selected, selection.candidates);
}

TEST(AdaptiveRefinement, UnmeasuredNodesAreSelectedAndOutOfRoiNeverAre) {
  const auto grid = grid_of(40, 40);
  auto field = field_on(grid, zero, 0.02);
  field.at(20, 20).flag = VectorFlag::kNoPeak;
  field.at(10, 10).flag = VectorFlag::kMasked;
  field.at(30, 5).flag = VectorFlag::kOutOfRoi;
  field.at(30, 5).u_px = 5;
  const auto selection = select_refinement(field, grid, field, grid, 4, 0);
  EXPECT_TRUE(selection.refine.at<std::uint8_t>(20, 20));
  EXPECT_TRUE(selection.refine.at<std::uint8_t>(10, 10));
  EXPECT_FALSE(selection.refine.at<std::uint8_t>(30, 5));
  EXPECT_EQ(selection.candidates, 40u * 40u - 1);
}

TEST(AdaptiveRefinement, ContextDilatesTheSelection) {
  const auto grid = grid_of(40, 40);
  auto field = field_on(grid, zero, 0.0);
  field.at(20, 20).flag = VectorFlag::kNoPeak;  // the one node to refine (a noise-free field: floor 0)
  const auto selection = select_refinement(field, grid, field, grid, 4, 3);
  EXPECT_EQ(selection.selected, 49u);
  EXPECT_TRUE(selection.refine.at<std::uint8_t>(17, 23));
  EXPECT_FALSE(selection.refine.at<std::uint8_t>(16, 20));
}

TEST(AdaptiveRefinement, ACoarseFirstPassSelectsTheFineNodesItInterpolates) {
  // Coarse nodes every 16 px from 7.5; fine ones every 8 px from 7.5.
  const auto coarse_grid = grid_of(20, 20, 16);
  const auto fine_grid = grid_of(39, 39, 8);
  auto coarse = field_on(coarse_grid, zero, 0.0);
  coarse.at(10, 10).flag = VectorFlag::kNoPeak;  // at x = y = 167.5: fine node 20
  const auto fine = field_on(fine_grid, zero, 0.0);
  const auto selection = select_refinement(coarse, coarse_grid, fine, fine_grid, 4, 0);
  // Fine nodes 19..21 interpolate from coarse node 10 (fine 18 and 22 lie on coarse 9 and 11).
  EXPECT_EQ(selection.selected, 9u);
  EXPECT_TRUE(selection.refine.at<std::uint8_t>(19, 21));
  EXPECT_FALSE(selection.refine.at<std::uint8_t>(18, 20));
}

TEST(AdaptiveRefinement, SmoothingAveragesTheUnrefinedNoiseAway) {
  const auto grid = grid_of(60, 60);
  auto field = field_on(grid, zero, 0.03);
  const cv::Mat refine = cv::Mat::zeros(grid.rows, grid.cols, CV_8U);
  smooth_unrefined(field, refine, 2);
  double sum_sq = 0;
  for (const auto& v : field.vectors) sum_sq += v.u_px * v.u_px + v.v_px * v.v_px;
  // A Gaussian of σ = 2 nodes averages about 4πσ² = 50 nodes: the noise drops ~7×.
  EXPECT_LT(std::sqrt(sum_sq / (2.0 * field.size())), 0.03 / 4);
}

// Against the definition, node by node, on a grid tall enough to be smoothed
// in bands (one per thread; rows near a band's edge are read by its
// neighbour unsmoothed), with refined and unmeasured nodes scattered in it.
TEST(AdaptiveRefinement, SmoothingIsTheGaussianMeanOfTheAveragedNodesInEveryBandLayout) {
  const auto grid = grid_of(150, 71);
  auto noisy = field_on(grid, bump(300, 500, 200, 0.5), 0.05);
  cv::Mat refine(grid.rows, grid.cols, CV_8U);
  cv::RNG rng(5);
  rng.fill(refine, cv::RNG::UNIFORM, 0, 4);
  refine = refine == 0;  // about a quarter refined
  for (int i = 0; i < 300; ++i) noisy.vectors[rng.uniform(0, int(noisy.size()))].flag = VectorFlag::kNoPeak;
  const double sigma = 2;
  const int half = 6;
  const cv::Mat g = cv::getGaussianKernel(2 * half + 1, sigma, CV_64F);
  auto averaged = [&](int r, int c) { return !refine.at<std::uint8_t>(r, c) && noisy.at(r, c).flag == VectorFlag::kOk; };
  const int threads = cv::getNumThreads();
  for (const int bands : {1, 2, 3, 7}) {
    cv::setNumThreads(bands);
    auto field = noisy;
    SmoothingBuffers buffers;
    smooth_unrefined(field, refine, sigma, buffers);
    for (int r = 0; r < grid.rows; ++r) {
      for (int c = 0; c < grid.cols; ++c) {
        if (!averaged(r, c)) {
          ASSERT_EQ(field.at(r, c).u_px, noisy.at(r, c).u_px) << r << "," << c;
          continue;
        }
        double w = 0, u = 0, v = 0;
        for (int dr = -half; dr <= half; ++dr) {
          for (int dc = -half; dc <= half; ++dc) {
            const int rr = r + dr, cc = c + dc;
            if (rr < 0 || cc < 0 || rr >= grid.rows || cc >= grid.cols || !averaged(rr, cc)) continue;
            const double weight = g.at<double>(dr + half) * g.at<double>(dc + half);
            w += weight;
            u += weight * noisy.at(rr, cc).u_px;
            v += weight * noisy.at(rr, cc).v_px;
          }
        }
        ASSERT_NEAR(field.at(r, c).u_px, u / w, 1e-12) << r << "," << c << ", " << bands << " bands";
        ASSERT_NEAR(field.at(r, c).v_px, v / w, 1e-12) << r << "," << c << ", " << bands << " bands";
      }
    }
  }
  cv::setNumThreads(threads);
}

TEST(AdaptiveRefinement, SmoothingLeavesRefinedNodesAndTakesNothingFromThem) {
  const auto grid = grid_of(40, 40);
  // Left half displaced by 1 px and refined; right half at 0, unrefined.
  auto field = field_on(
      grid, [](double x, double) { return cv::Point2d(x < 160 ? 1.0 : 0.0, 0); }, 0.0);
  cv::Mat refine = cv::Mat::zeros(grid.rows, grid.cols, CV_8U);
  refine.colRange(0, 20).setTo(1);
  field.at(5, 30).flag = VectorFlag::kNoTexture;  // unmeasured: neither changed nor averaged in
  field.at(5, 30).u_px = 7;
  const auto before = field;
  smooth_unrefined(field, refine, 2);
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      EXPECT_EQ(field.at(r, c).u_px, before.at(r, c).u_px) << r << "," << c;  // 1 left, 0 right, 7 at (5, 30)
    }
  }
  auto unchanged = before;
  smooth_unrefined(unchanged, cv::Mat::zeros(grid.rows, grid.cols, CV_8U), 0);
  EXPECT_EQ(unchanged.at(3, 3).u_px, before.at(3, 3).u_px);
  EXPECT_THROW(smooth_unrefined(unchanged, refine, -1), std::invalid_argument);
  EXPECT_THROW(smooth_unrefined(unchanged, cv::Mat::zeros(3, 3, CV_8U), 2), std::invalid_argument);
}

TEST(AdaptiveRefinement, BadArgumentsAreNamed) {
  const auto grid = grid_of(4, 4);
  const auto field = field_on(grid, zero, 0.01);
  EXPECT_THROW(select_refinement(field, grid, field, grid, 0, 1), std::invalid_argument);
  EXPECT_THROW(select_refinement(field, grid, field, grid, 4, -1), std::invalid_argument);
  EXPECT_THROW(select_refinement(field, grid_of(5, 4), field, grid, 4, 1), std::invalid_argument);
  EXPECT_EQ(refinement_context_nodes(16, 2, 8), 4);  // ceil((8 + 2 + 4) / 8) + 2
}

}  // namespace
}  // namespace bosfuse::fusion
