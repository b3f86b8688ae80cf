#include "fusion/outlier_filter.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "fusion/eight_neighbours.h"
#include "fusion/for_rows.h"
#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {
namespace {

bool has_value(VectorFlag flag) { return flag == VectorFlag::kOk || flag == VectorFlag::kOutlierReplaced; }

// Sorts eight values with the 19 compare-exchanges of the optimal network
// (Knuth, TAOCP 5.3.4): branch-free min/max, where an insertion sort of an
// interior node's eight neighbours mispredicts about every other step.
void sort_eight(double* v) {
  static constexpr int kPairs[19][2] = {{0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {0, 1}, {2, 3},
                                        {4, 5}, {6, 7}, {2, 4}, {3, 5}, {1, 4}, {3, 6}, {1, 2}, {3, 4}, {5, 6}};
  // Unrolled, the eight values stay in registers.
#pragma GCC unroll 19
  for (const auto& [i, j] : kPairs) {
    const double low = std::min(v[i], v[j]), high = std::max(v[i], v[j]);
    v[i] = low;
    v[j] = high;
  }
}

// Normalised residual of one component against its neighbours.
double normalised_residual(double value, std::array<double, 8> neighbours, int count, double epsilon_px) {
  const double med = median_in_place(neighbours.data(), count);
  std::array<double, 8> residuals{};
  for (int i = 0; i < count; ++i) residuals[i] = std::abs(neighbours[i] - med);
  return std::abs(value - med) / (median_in_place(residuals.data(), count) + epsilon_px);
}

}  // namespace

// The same value whichever way the middle is found. A node has at most 8
// neighbours: sorting them by a network or by insertion costs a fraction of
// nth_element and max_element on so few (the test runs twice per component,
// per node and pass: 4 % of a 16 MP frame's time before).
double median_in_place(double* begin, int n) {
  if (n <= 0) return std::numeric_limits<double>::quiet_NaN();
  if (n == 8) {
    sort_eight(begin);
    return 0.5 * (begin[3] + begin[4]);
  }
  if (n < 8) {
    for (int i = 1; i < n; ++i) {
      const double value = begin[i];
      int j = i;
      for (; j > 0 && begin[j - 1] > value; --j) begin[j] = begin[j - 1];
      begin[j] = value;
    }
    return n % 2 == 1 ? begin[n / 2] : 0.5 * (begin[n / 2 - 1] + begin[n / 2]);
  }
  std::nth_element(begin, begin + n / 2, begin + n);
  const double upper = begin[n / 2];
  if (n % 2 == 1) return upper;
  const double lower = *std::max_element(begin, begin + n / 2);
  return 0.5 * (lower + upper);
}

double median_of_non_negative(std::span<const double> values) {
  const std::size_t n = values.size();
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  const auto bucket_of = [](double v) { return static_cast<std::size_t>(std::bit_cast<std::uint64_t>(v) >> 48); };
  std::vector<std::uint32_t> histogram(std::size_t{1} << 16, 0);
  for (const double v : values) ++histogram[bucket_of(v)];
  std::vector<double> in_bucket;
  const auto value_of_rank = [&](std::size_t rank) {  // 0 the least
    std::size_t below = 0, bucket = 0;
    for (; below + histogram[bucket] <= rank; ++bucket) below += histogram[bucket];
    in_bucket.clear();
    for (const double v : values) {
      if (bucket_of(v) == bucket) in_bucket.push_back(v);
    }
    const auto nth = in_bucket.begin() + static_cast<std::ptrdiff_t>(rank - below);
    std::nth_element(in_bucket.begin(), nth, in_bucket.end());
    return *nth;
  };
  const double upper = value_of_rank(n / 2);
  return n % 2 == 1 ? upper : 0.5 * (value_of_rank(n / 2 - 1) + upper);
}

std::string OutlierOptions::Validate() const {
  if (!(threshold > 0)) return "outlier threshold must be positive";
  if (!(epsilon_px >= 0)) return "outlier epsilon must not be negative";
  if (min_neighbours < 1 || min_neighbours > 8) return "outlier test needs 1 to 8 neighbours";
  return {};
}

std::size_t replace_outliers(DisplacementField& field, const OutlierOptions& options, const cv::Mat* only,
                             const cv::Mat* replace_in) {
  const auto fits = [&](const cv::Mat* mask) {
    return !mask || (mask->rows == field.rows && mask->cols == field.cols && mask->type() == CV_8U);
  };
  if (!fits(only)) throw std::invalid_argument("outlier test: the nodes to test do not match the field");
  if (!fits(replace_in)) throw std::invalid_argument("outlier test: the nodes to replace do not match the field");
  auto measured = [](const DisplacementVector& v) { return v.flag == VectorFlag::kOk; };
  // Nothing is written before every test and every replacement value is
  // known, so all of them read the field as it came, rows in parallel, with
  // no 12 MB copy of a 16 MP frame's field.
  std::vector<std::uint8_t> is_outlier(field.vectors.size(), 0);
  // |(ru, rv)| > threshold without hypot's care for overflow, which costs
  // more than the rest of the test: an overflowing square is infinite and
  // so still above the threshold.
  const auto outlier = [&](double ru, double rv) { return ru * ru + rv * rv > options.threshold * options.threshold; };
  for_rows(field.rows, [&](int row) {
    const std::uint8_t* tested = only ? only->ptr<std::uint8_t>(row) : nullptr;
    EightNeighbourBlock block;
    auto test_block = [&] {
      std::array<double, EightNeighbourBlock::kNodes> ru, rv;
      normalised_residuals_of_eight(block.u.data(), block.kNodes, block.count, block.centre_u.data(),
                                    options.epsilon_px, ru.data());
      normalised_residuals_of_eight(block.v.data(), block.kNodes, block.count, block.centre_v.data(),
                                    options.epsilon_px, rv.data());
      for (int j = 0; j < block.count; ++j) is_outlier[block.index[j]] = outlier(ru[j], rv[j]);
      block.count = 0;
    };
    for (int col = 0; col < field.cols; ++col) {
      if (tested && !tested[col]) continue;  // before the vector: under adaptive refinement most are not
      const auto& vec = field.at(row, col);
      if (!measured(vec)) continue;
      const bool on_edge = row == 0 || col == 0 || row == field.rows - 1 || col == field.cols - 1;
      if (on_edge && !options.test_grid_edges) continue;
      // The usual case, eight measured neighbours: many nodes' medians at once.
      if (!on_edge && block.add_if_all_measured(field, row, col)) {
        if (block.full()) test_block();
        continue;
      }
      const Neighbours n = neighbours_of(field, row, col, measured);
      if (n.count < options.min_neighbours) continue;
      is_outlier[static_cast<std::size_t>(row) * field.cols + col] =
          outlier(normalised_residual(vec.u_px, n.u, n.count, options.epsilon_px),
                  normalised_residual(vec.v_px, n.v, n.count, options.epsilon_px));
    }
    if (block.count > 0) test_block();
  });
  std::vector<std::size_t> outliers;
  for (std::size_t i = 0; i < is_outlier.size(); ++i) {
    if (is_outlier[i]) outliers.push_back(i);
  }
  std::vector<std::size_t> replaced;
  for (const std::size_t i : outliers) {
    if (!replace_in || replace_in->data[i]) replaced.push_back(i);
  }
  std::vector<cv::Point2d> replacements(replaced.size());
  for (std::size_t k = 0; k < replaced.size(); ++k) {
    const std::size_t i = replaced[k];
    const int row = static_cast<int>(i / field.cols), col = static_cast<int>(i % field.cols);
    // Replace from neighbours that are not outliers themselves.
    Neighbours n = neighbours_of(field, row, col, [&](const DisplacementVector& v) {
      return measured(v) &&
             !std::binary_search(outliers.begin(), outliers.end(), static_cast<std::size_t>(&v - field.vectors.data()));
    });
    if (n.count == 0) n = neighbours_of(field, row, col, measured);
    replacements[k] = {median_in_place(n.u.data(), n.count), median_in_place(n.v.data(), n.count)};
  }
  for (std::size_t k = 0; k < replaced.size(); ++k) {
    auto& vec = field.vectors[replaced[k]];
    vec.u_px = replacements[k].x;
    vec.v_px = replacements[k].y;
    vec.flag = VectorFlag::kOutlierReplaced;
  }
  return replaced.size();
}

namespace {

// 1.4826 × the median absolute deviation of values[0 … count) (the
// standard deviation of normally distributed values), reordering them.
double robust_spread(double* values, int count) {
  const double med = median_in_place(values, count);
  for (int i = 0; i < count; ++i) values[i] = std::abs(values[i] - med);
  return 1.4826 * median_in_place(values, count);
}

}  // namespace

void estimate_replaced_uncertainty(DisplacementField& field, const cv::Mat* only) {
  for_rows(field.rows, [&](int row) {
    const std::uint8_t* marked = only ? only->ptr<std::uint8_t>(row) : nullptr;
    for (int col = 0; col < field.cols; ++col) {
      if (marked && !marked[col]) continue;
      auto& vec = field.at(row, col);
      if (vec.flag != VectorFlag::kOutlierReplaced) continue;
      std::array<double, 8> sigma_u{}, sigma_v{};
      int with_sigma = 0;
      Neighbours n = neighbours_of(field, row, col, [&](const DisplacementVector& v) {
        if (v.flag != VectorFlag::kOk) return false;
        if (v.sigma_u_px > 0 && v.sigma_v_px > 0) {
          sigma_u[with_sigma] = v.sigma_u_px;
          sigma_v[with_sigma] = v.sigma_v_px;
          ++with_sigma;
        }
        return true;
      });
      if (n.count == 0) continue;  // replaced from none: cannot happen, but then nothing to say
      const double own_u = with_sigma > 0 ? median_in_place(sigma_u.data(), with_sigma) : 0.0;
      const double own_v = with_sigma > 0 ? median_in_place(sigma_v.data(), with_sigma) : 0.0;
      vec.sigma_u_px = std::hypot(robust_spread(n.u.data(), n.count), own_u);
      vec.sigma_v_px = std::hypot(robust_spread(n.v.data(), n.count), own_v);
    }
  });
}

GridField predictor_from(const DisplacementField& field, const GridGeometry& grid, int max_sweeps) {
  GridField predictor;
  predictor_from(field, grid, predictor, max_sweeps);
  return predictor;
}

void predictor_from(const DisplacementField& field, const GridGeometry& grid, GridField& predictor, int max_sweeps) {
  predictor.grid = grid;
  predictor.u_px.create(field.rows, field.cols, CV_64F);
  predictor.v_px.create(field.rows, field.cols, CV_64F);
  cv::Mat filled(field.rows, field.cols, CV_8U);
  std::atomic<bool> gaps{false};
  // Every node written here, on both cores: no serial zero fill first.
  for_rows(field.rows, [&](int row) {
    bool row_has_gap = false;
    double* u = predictor.u_px.ptr<double>(row);
    double* v = predictor.v_px.ptr<double>(row);
    std::uint8_t* has = filled.ptr<std::uint8_t>(row);
    for (int col = 0; col < field.cols; ++col) {
      const auto& vec = field.at(row, col);
      has[col] = has_value(vec.flag);
      u[col] = has[col] ? vec.u_px : 0.0;
      v[col] = has[col] ? vec.v_px : 0.0;
      row_has_gap = row_has_gap || !has[col];
    }
    if (row_has_gap) gaps = true;
  });
  // A field with a value at every node (the usual case) needs no filling,
  // nor the copy of it that filling works on.
  if (!gaps) return;
  DisplacementField work = field;  // flags double as "has a value" below
  for (std::size_t i = 0; i < work.vectors.size(); ++i) {
    if (filled.data[i]) work.vectors[i].flag = VectorFlag::kOk;
  }
  for (int sweep = 0; sweep < max_sweeps; ++sweep) {
    std::vector<std::pair<std::size_t, cv::Point2d>> updates;
    for (int row = 0; row < field.rows; ++row) {
      for (int col = 0; col < field.cols; ++col) {
        if (filled.at<std::uint8_t>(row, col)) continue;
        Neighbours n =
            neighbours_of(work, row, col, [](const DisplacementVector& v) { return v.flag == VectorFlag::kOk; });
        if (n.count == 0) continue;
        updates.push_back({static_cast<std::size_t>(row) * field.cols + col,
                           {median_in_place(n.u.data(), n.count), median_in_place(n.v.data(), n.count)}});
      }
    }
    if (updates.empty()) break;
    for (const auto& [i, value] : updates) {
      const int row = static_cast<int>(i / field.cols), col = static_cast<int>(i % field.cols);
      predictor.u_px.at<double>(row, col) = value.x;
      predictor.v_px.at<double>(row, col) = value.y;
      filled.at<std::uint8_t>(row, col) = 1;
      work.vectors[i] = {0, 0, value.x, value.y, 0, VectorFlag::kOk};
    }
  }
}

bool predictor_at(const DisplacementField& field, const GridGeometry& grid, GridField& predictor, const cv::Mat& only) {
  predictor.grid = grid;
  predictor.u_px.create(field.rows, field.cols, CV_64F);
  predictor.v_px.create(field.rows, field.cols, CV_64F);
  std::atomic<bool> gap{false};
  for_marked(only, [&](int row, int col) {
    const auto& vec = field.at(row, col);
    if (!has_value(vec.flag)) gap.store(true, std::memory_order_relaxed);
    predictor.u_px.at<double>(row, col) = vec.u_px;
    predictor.v_px.at<double>(row, col) = vec.v_px;
  });
  return !gap;
}

namespace {

// The binomial kernel's taps along one axis at node `i` of `n`. Inside,
// 1-2-1. At the outermost node the kernel is one-sided: (3, 2, −1)/4 over
// the node and its two inner neighbours reproduces a linear field (a
// truncated 1-2-1, (2, 1)/3, pulls the edge node a third of a node step's
// gradient inwards, which the deformed passes do not undo) and, like 1-2-1,
// removes the grid's Nyquist component (3 − 2 − 1 = 0).
struct AxisTaps {
  int count = 0;
  int index[3] = {};
  double weight[3] = {};
};

AxisTaps axis_taps(int i, int n) {
  if (n == 1) return {1, {i}, {1.0}};
  if (i > 0 && i + 1 < n) return {3, {i - 1, i, i + 1}, {0.25, 0.5, 0.25}};
  const int inward = i == 0 ? 1 : -1;
  if (n == 2) return {1, {i}, {1.0}};  // too few nodes for a linear one-sided kernel
  return {3, {i, i + inward, i + 2 * inward}, {0.75, 0.5, -0.25}};
}

}  // namespace

void mark_smoothing_taps(const cv::Mat& nodes, cv::Mat& taps) {
  CV_Assert(nodes.type() == CV_8U);
  taps = cv::Mat::zeros(nodes.size(), CV_8U);
  for (int row = 0; row < nodes.rows; ++row) {
    for (int col = 0; col < nodes.cols; ++col) {
      if (!nodes.at<std::uint8_t>(row, col)) continue;
      const AxisTaps along_rows = axis_taps(row, nodes.rows), along_cols = axis_taps(col, nodes.cols);
      for (int i = 0; i < along_rows.count; ++i) {
        for (int j = 0; j < along_cols.count; ++j) taps.at<std::uint8_t>(along_rows.index[i], along_cols.index[j]) = 1;
      }
    }
  }
}

void smooth_predictor(GridField& predictor) {
  cv::Mat scratch;
  smooth_predictor(predictor, scratch);
}

void smooth_predictor(GridField& predictor, cv::Mat& scratch, const cv::Mat* only) {
  for (cv::Mat* values : {&predictor.u_px, &predictor.v_px}) {
    // The smoothed values into `scratch`, which then becomes the component
    // (and the component's buffer the next scratch).
    const cv::Mat source = *values;
    if (scratch.data == source.data) scratch.release();
    scratch.create(source.rows, source.cols, CV_64F);
    const auto at_edge = [&](int row, int col) {
      const AxisTaps along_rows = axis_taps(row, source.rows), along_cols = axis_taps(col, source.cols);
      double sum = 0;
      for (int i = 0; i < along_rows.count; ++i) {
        const double* values_row = source.ptr<double>(along_rows.index[i]);
        double row_sum = 0;
        for (int j = 0; j < along_cols.count; ++j) row_sum += along_cols.weight[j] * values_row[along_cols.index[j]];
        sum += along_rows.weight[i] * row_sum;
      }
      return sum;
    };
    // Inside the grid every tap is there: the same sums in the same order,
    // without the tests, and the weights add up to 16.
    const auto inside = [](const double* above, const double* here, const double* below, int c) {
      double sum = 0;
      sum += above[c - 1];
      sum += 2 * above[c];
      sum += above[c + 1];
      sum += 2 * here[c - 1];
      sum += 4 * here[c];
      sum += 2 * here[c + 1];
      sum += below[c - 1];
      sum += 2 * below[c];
      sum += below[c + 1];
      return sum / 16;
    };
    // Nodes [first, last) of a row; their inner part in one loop the
    // compiler vectorises.
    const auto smooth_run = [&](int row, int first, int last) {
      double* out = scratch.ptr<double>(row);
      if (row == 0 || row + 1 == source.rows || source.cols < 3) {
        for (int col = first; col < last; ++col) out[col] = at_edge(row, col);
        return;
      }
      const double *above = source.ptr<double>(row - 1), *here = source.ptr<double>(row),
                   *below = source.ptr<double>(row + 1);
      if (first == 0) out[0] = at_edge(row, 0);
      const int inner_end = std::min(last, source.cols - 1);
      for (int c = std::max(first, 1); c < inner_end; ++c) out[c] = inside(above, here, below, c);
      if (last == source.cols) out[source.cols - 1] = at_edge(row, source.cols - 1);
    };
    for_row_runs(source.rows, source.cols, only, smooth_run);
    cv::swap(*values, scratch);
  }
}

}  // namespace bosfuse::fusion
