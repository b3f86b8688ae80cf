#include "fusion/outlier_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <vector>

namespace bosfuse::fusion {
namespace {

DisplacementField smooth_field(int rows, int cols) {
  DisplacementField field;
  field.rows = rows;
  field.cols = cols;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      // A gentle gradient with a little noise: nothing here is an outlier.
      field.vectors.push_back(
          {double(c), double(r), 0.5 + 0.01 * c + 0.003 * ((r * 7 + c * 3) % 5), 0.2, 5, VectorFlag::kOk});
    }
  }
  return field;
}

// Each way of finding the middle (network, insertion, nth_element) against
// a full sort: equal exactly, ties and negative values included.
TEST(OutlierFilter, TheMedianIsTheSortedMiddleForEveryCount) {
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> level(-4, 4);
  for (const int count : {1, 2, 3, 5, 7, 8, 9, 16, 101}) {
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<double> values(static_cast<std::size_t>(count));
      for (double& v : values) v = 0.25 * level(rng) + (trial % 2 ? 1e-3 * level(rng) : 0.0);
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      const double expected = count % 2 ? sorted[count / 2] : 0.5 * (sorted[count / 2 - 1] + sorted[count / 2]);
      ASSERT_EQ(median_in_place(values.data(), count), expected) << count << " values, trial " << trial;
    }
  }
  EXPECT_TRUE(std::isnan(median_in_place(nullptr, 0)));
}

// Against median_in_place on residual-like values: spread over decades (many
// buckets), all in one narrow range (one bucket), ties, zeros, infinities.
TEST(OutlierFilter, TheMedianOfNonNegativeValuesIsTheMedianOfThem) {
  std::mt19937 rng(37);
  std::lognormal_distribution<double> spread(-4, 2);
  std::uniform_int_distribution<int> level(0, 6);
  for (const int count : {1, 2, 3, 4, 17, 1000, 1001, 125'000}) {
    for (int kind = 0; kind < 4; ++kind) {
      std::vector<double> values(static_cast<std::size_t>(count));
      for (double& v : values) {
        v = kind == 0 ? spread(rng) : kind == 1 ? 1.0 + 1e-9 * level(rng) : kind == 2 ? 0.5 * level(rng) : 0.0;
      }
      if (kind == 3 && count > 2) values[1] = std::numeric_limits<double>::infinity();
      std::vector<double> copy = values;
      const double expected = median_in_place(copy.data(), count);
      ASSERT_EQ(median_of_non_negative(values), expected) << count << " values, kind " << kind;
    }
  }
  EXPECT_TRUE(std::isnan(median_of_non_negative({})));
}

TEST(OutlierFilter, ReplacesASpuriousVectorWithItsNeighboursMedian) {
  DisplacementField field = smooth_field(7, 7);
  field.at(3, 3).u_px = 4.0;
  field.at(3, 3).v_px = -2.0;
  EXPECT_EQ(replace_outliers(field, OutlierOptions{}), 1u);
  EXPECT_EQ(field.at(3, 3).flag, VectorFlag::kOutlierReplaced);
  EXPECT_NEAR(field.at(3, 3).u_px, 0.53, 0.02);
  EXPECT_NEAR(field.at(3, 3).v_px, 0.2, 1e-12);
  EXPECT_EQ(field.count(VectorFlag::kOk), 48u);
}

TEST(OutlierFilter, TheGridEdgeIsTestedOnlyOnRequest) {
  DisplacementField field = smooth_field(7, 7);
  field.at(0, 3).u_px = 4.0;
  DisplacementField untouched = field;
  EXPECT_EQ(replace_outliers(untouched, OutlierOptions{}), 0u);
  EXPECT_EQ(untouched.at(0, 3).u_px, 4.0);
  OutlierOptions options;
  options.test_grid_edges = true;
  EXPECT_EQ(replace_outliers(field, options), 1u);
  EXPECT_EQ(field.at(0, 3).flag, VectorFlag::kOutlierReplaced);
  EXPECT_NEAR(field.at(0, 3).u_px, 0.53, 0.02);
}

TEST(OutlierFilter, LeavesASmoothFieldAlone) {
  DisplacementField field = smooth_field(6, 9);
  const DisplacementField before = field;
  EXPECT_EQ(replace_outliers(field, OutlierOptions{}), 0u);
  for (std::size_t i = 0; i < field.size(); ++i) EXPECT_EQ(field.vectors[i].u_px, before.vectors[i].u_px);
}

// Adaptive refinement tests only the refined nodes, grown by one: there the
// result must be the whole field's, clusters of outliers and outliers on the
// marked region's border included, and nothing unmarked may change.
TEST(OutlierFilter, TestingOnlyMarkedNodesLeavesThemAsTheWholeFieldsTestDoes) {
  std::mt19937 random(5);
  std::bernoulli_distribution spurious(0.08);
  std::normal_distribution<double> wild(0.0, 3.0);
  DisplacementField field = smooth_field(40, 50);
  for (auto& vec : field.vectors) {
    if (spurious(random)) vec.u_px += wild(random);
  }
  cv::Mat marked = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  cv::circle(marked, {20, 18}, 11, cv::Scalar(1), cv::FILLED);
  cv::Mat tested;
  cv::dilate(marked, tested, cv::Mat::ones(3, 3, CV_8U));
  DisplacementField whole = field, restricted = field;
  const std::size_t replaced_whole = replace_outliers(whole, OutlierOptions{});
  const std::size_t replaced_restricted = replace_outliers(restricted, OutlierOptions{}, &tested);
  ASSERT_GT(replaced_restricted, 10u);
  ASSERT_LT(replaced_restricted, replaced_whole);
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& got = restricted.at(r, c);
      const auto& want = marked.at<std::uint8_t>(r, c) ? whole.at(r, c) : field.at(r, c);
      if (tested.at<std::uint8_t>(r, c) && !marked.at<std::uint8_t>(r, c)) continue;  // the ring: tested, not kept
      ASSERT_EQ(got.u_px, want.u_px) << r << ", " << c;
      ASSERT_EQ(got.v_px, want.v_px) << r << ", " << c;
      ASSERT_EQ(got.flag, want.flag) << r << ", " << c;
    }
  }
  // Replacing only the marked nodes: those end as above, the ring as it came
  // (where the test above replaced some).
  std::size_t ring_replaced = 0;
  for (std::size_t i = 0; i < field.vectors.size(); ++i) {
    ring_replaced += tested.data[i] && !marked.data[i] && restricted.vectors[i].flag == VectorFlag::kOutlierReplaced;
  }
  ASSERT_GT(ring_replaced, 0u);
  DisplacementField kept = field;
  replace_outliers(kept, OutlierOptions{}, &tested, &marked);
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& want = marked.at<std::uint8_t>(r, c) ? whole.at(r, c) : field.at(r, c);
      ASSERT_EQ(kept.at(r, c).u_px, want.u_px) << r << ", " << c;
      ASSERT_EQ(kept.at(r, c).flag, want.flag) << r << ", " << c;
    }
  }
  const cv::Mat wrong_size = cv::Mat::ones(field.rows, field.cols + 1, CV_8U);
  EXPECT_THROW(replace_outliers(restricted, OutlierOptions{}, &wrong_size), std::invalid_argument);
  EXPECT_THROW(replace_outliers(restricted, OutlierOptions{}, &tested, &wrong_size), std::invalid_argument);
}

// The normalised median test as written down (Westerweel & Scarano 2005):
// sorted medians of the measured neighbours, one node at a time.
std::vector<std::uint8_t> plain_outliers(const DisplacementField& field, const OutlierOptions& options) {
  auto median = [](std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  };
  auto residual = [&](double value, const std::vector<double>& neighbours) {
    const double m = median(neighbours);
    std::vector<double> deviations;
    for (const double x : neighbours) deviations.push_back(std::abs(x - m));
    return std::abs(value - m) / (median(deviations) + options.epsilon_px);
  };
  std::vector<std::uint8_t> outlier(field.vectors.size(), 0);
  for (int r = 1; r + 1 < field.rows; ++r) {
    for (int c = 1; c + 1 < field.cols; ++c) {
      if (field.at(r, c).flag != VectorFlag::kOk) continue;
      std::vector<double> u, v;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const auto& n = field.at(r + dr, c + dc);
          if ((dr || dc) && n.flag == VectorFlag::kOk) u.push_back(n.u_px), v.push_back(n.v_px);
        }
      }
      if (static_cast<int>(u.size()) < options.min_neighbours) continue;
      outlier[static_cast<std::size_t>(r) * field.cols + c] =
          std::hypot(residual(field.at(r, c).u_px, u), residual(field.at(r, c).v_px, v)) > options.threshold;
    }
  }
  return outlier;
}

// A noisy field with spurious and unmeasured vectors: nodes with all eight
// neighbours measured (tested many at once) and with fewer (one by one) are
// replaced exactly where the plain test finds outliers, and nowhere else.
TEST(OutlierFilter, FlagsWhatThePlainNormalisedMedianTestFlags) {
  std::mt19937 random(11);
  std::normal_distribution<double> noise(0.0, 0.05), wild(0.0, 2.0);
  std::bernoulli_distribution spurious(0.06), missing(0.04);
  DisplacementField field = smooth_field(37, 53);
  for (auto& vec : field.vectors) {
    vec.u_px += noise(random) + (spurious(random) ? wild(random) : 0.0);
    vec.v_px += noise(random);
    if (missing(random)) vec.flag = VectorFlag::kNoPeak;
  }
  const OutlierOptions options;
  const std::vector<std::uint8_t> expected = plain_outliers(field, options);
  DisplacementField tested = field;
  const std::size_t replaced = replace_outliers(tested, options);
  ASSERT_GT(replaced, 40u);
  for (std::size_t i = 0; i < field.vectors.size(); ++i) {
    ASSERT_EQ(tested.vectors[i].flag == VectorFlag::kOutlierReplaced, expected[i] == 1) << "node " << i;
  }
}

TEST(OutlierFilter, PredictorFillsGapsFromNeighbours) {
  DisplacementField field = smooth_field(5, 5);
  for (int c = 0; c < 5; ++c) field.at(2, c).flag = VectorFlag::kMasked;
  field.at(2, 2).u_px = 99;  // must not leak into the predictor
  const GridField predictor = predictor_from(field, {0, 0, 1, 5, 5});
  EXPECT_NEAR(predictor.u_px.at<double>(2, 2), 0.52, 0.02);
  EXPECT_NEAR(predictor.v_px.at<double>(2, 2), 0.2, 1e-12);
}

// An interior node's eight neighbours are sorted by a network: its median is
// the sorted middle pair's mean, ties and repeated values included.
TEST(OutlierFilter, AMissingNodeTakesTheMedianOfItsEightNeighbours) {
  std::mt19937 random(11);
  std::uniform_int_distribution<int> coarse(-3, 3);  // many ties
  std::normal_distribution<double> fine(0.0, 2.0);
  for (int trial = 0; trial < 500; ++trial) {
    DisplacementField field = smooth_field(3, 3);
    std::vector<double> u, v;
    for (auto& vec : field.vectors) {
      vec.u_px = trial % 2 ? coarse(random) : fine(random);
      vec.v_px = trial % 2 ? fine(random) : coarse(random);
      if (&vec == &field.at(1, 1)) continue;
      u.push_back(vec.u_px);
      v.push_back(vec.v_px);
    }
    field.at(1, 1).flag = VectorFlag::kNoPeak;
    const GridField predictor = predictor_from(field, {0, 0, 1, 3, 3});
    std::sort(u.begin(), u.end());
    std::sort(v.begin(), v.end());
    ASSERT_EQ(predictor.u_px.at<double>(1, 1), 0.5 * (u[3] + u[4])) << "trial " << trial;
    ASSERT_EQ(predictor.v_px.at<double>(1, 1), 0.5 * (v[3] + v[4])) << "trial " << trial;
  }
}

// At the marked nodes the restricted predictor and smoothing equal the
// whole field's, to the bit; the other nodes keep what the buffers held;
// a gap under the mask refuses the restricted predictor (whose caller then
// takes the whole one).
TEST(OutlierFilter, APredictorAtMarkedNodesIsTheWholePredictorThere) {
  DisplacementField field = smooth_field(9, 12);
  std::mt19937 random(3);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (auto& vec : field.vectors) vec.u_px += noise(random);
  field.at(0, 11).flag = VectorFlag::kNoPeak;  // a gap outside the mask
  const GridGeometry grid{0, 0, 1, 9, 12};
  cv::Mat marked = cv::Mat::zeros(9, 12, CV_8U);
  marked(cv::Rect(2, 1, 6, 5)).setTo(1);
  // Runs at the grid's edges and of one node: the smoothing's edge taps.
  for (const cv::Rect run : {cv::Rect(0, 7, 1, 1), cv::Rect(9, 8, 3, 1), cv::Rect(10, 3, 1, 1), cv::Rect(11, 5, 1, 1)}) {
    marked(run).setTo(1);
  }
  cv::Mat around;
  mark_smoothing_taps(marked, around);

  GridField whole = predictor_from(field, grid);
  constexpr double kUntouched = -777;
  GridField part{grid, cv::Mat(9, 12, CV_64F, cv::Scalar(kUntouched)), cv::Mat(9, 12, CV_64F, cv::Scalar(kUntouched))};
  ASSERT_TRUE(predictor_at(field, grid, part, around));
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 12; ++c) {
      const double want = around.at<std::uint8_t>(r, c) ? whole.u_px.at<double>(r, c) : kUntouched;
      ASSERT_EQ(part.u_px.at<double>(r, c), want) << r << ", " << c;
    }
  }
  cv::Mat whole_scratch;
  smooth_predictor(whole, whole_scratch);
  cv::Mat scratch(9, 12, CV_64F, cv::Scalar(kUntouched));
  smooth_predictor(part, scratch, &marked);
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 12; ++c) {
      if (marked.at<std::uint8_t>(r, c)) {
        ASSERT_EQ(part.u_px.at<double>(r, c), whole.u_px.at<double>(r, c)) << r << ", " << c;
        ASSERT_EQ(part.v_px.at<double>(r, c), whole.v_px.at<double>(r, c)) << r << ", " << c;
      } else {
        ASSERT_EQ(part.u_px.at<double>(r, c), kUntouched) << r << ", " << c;
      }
    }
  }
  field.at(3, 4).flag = VectorFlag::kNoPeak;  // a gap under the mask: it must be filled from neighbours
  GridField refused{grid, cv::Mat(9, 12, CV_64F, cv::Scalar(kUntouched)),
                    cv::Mat(9, 12, CV_64F, cv::Scalar(kUntouched))};
  EXPECT_FALSE(predictor_at(field, grid, refused, around));
  EXPECT_EQ(cv::countNonZero(refused.u_px != kUntouched), cv::countNonZero(around)) << "only the marked nodes written";
}

TEST(OutlierFilter, NothingMeasuredGivesAZeroPredictor) {
  DisplacementField field = smooth_field(3, 3);
  for (auto& v : field.vectors) v.flag = VectorFlag::kNoTexture;
  const GridField predictor = predictor_from(field, {0, 0, 1, 3, 3});
  EXPECT_EQ(cv::countNonZero(predictor.u_px), 0);
}

// At every node, the outermost ones included: a truncated 1-2-1 at the edge
// pulled a linear field a third of its node-to-node change inwards there.
TEST(OutlierFilter, SmoothingKeepsALinearFieldAndRemovesACheckerboard) {
  GridField field{{0, 0, 1, 6, 7}, cv::Mat(6, 7, CV_64F), cv::Mat(6, 7, CV_64F)};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 7; ++c) {
      field.u_px.at<double>(r, c) = 0.1 * c - 0.07 * r + 0.3;
      field.v_px.at<double>(r, c) = (r + c) % 2 ? 0.05 : -0.05;
    }
  }
  smooth_predictor(field);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 7; ++c) {
      EXPECT_NEAR(field.u_px.at<double>(r, c), 0.1 * c - 0.07 * r + 0.3, 1e-12) << r << ", " << c;
      EXPECT_NEAR(field.v_px.at<double>(r, c), 0.0, 1e-12) << r << ", " << c;
    }
  }
}

// The kernel along one axis at node i of n, written out: 1-2-1 inside,
// (3, 2, −1)/4 towards the inside at the edge, the node alone on grids of
// one or two nodes.
std::vector<std::pair<int, double>> expected_taps(int i, int n) {
  if (n <= 2) return {{i, 1.0}};
  if (i == 0) return {{0, 0.75}, {1, 0.5}, {2, -0.25}};
  if (i == n - 1) return {{n - 1, 0.75}, {n - 2, 0.5}, {n - 3, -0.25}};
  return {{i - 1, 0.25}, {i, 0.5}, {i + 1, 0.25}};
}

// Every node, edge or not, is the product kernel of expected_taps over its
// neighbourhood, on grids too thin to have an inside as well; the nodes
// mark_smoothing_taps gives are the ones it reads.
TEST(OutlierFilter, SmoothingIsTheSeparableKernelAtEveryNode) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> value(-3, 3);
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(5, 1), cv::Size(1, 4), cv::Size(2, 2), cv::Size(7, 2),
                              cv::Size(3, 3), cv::Size(11, 7)}) {
    GridField field{{0, 0, 1, size.height, size.width}, cv::Mat(size, CV_64F), cv::Mat(size, CV_64F)};
    for (cv::Mat* m : {&field.u_px, &field.v_px}) {
      for (int i = 0; i < size.area(); ++i) m->at<double>(i) = value(rng);
    }
    const GridField before{field.grid, field.u_px.clone(), field.v_px.clone()};
    smooth_predictor(field);
    for (int r = 0; r < size.height; ++r) {
      for (int c = 0; c < size.width; ++c) {
        double u = 0, v = 0;
        cv::Mat node = cv::Mat::zeros(size, CV_8U), read = cv::Mat::zeros(size, CV_8U), taps;
        node.at<std::uint8_t>(r, c) = 1;
        for (const auto& [row, wr] : expected_taps(r, size.height)) {
          for (const auto& [col, wc] : expected_taps(c, size.width)) {
            u += wr * wc * before.u_px.at<double>(row, col);
            v += wr * wc * before.v_px.at<double>(row, col);
            read.at<std::uint8_t>(row, col) = 1;
          }
        }
        ASSERT_NEAR(field.u_px.at<double>(r, c), u, 1e-12) << size << " at " << r << ", " << c;
        ASSERT_NEAR(field.v_px.at<double>(r, c), v, 1e-12) << size << " at " << r << ", " << c;
        mark_smoothing_taps(node, taps);
        ASSERT_EQ(cv::countNonZero(taps != read), 0) << size << " at " << r << ", " << c;
      }
    }
  }
}

}  // namespace
}  // namespace bosfuse::fusion
