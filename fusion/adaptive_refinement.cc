#include "fusion/adaptive_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>
#include <vector>

#include "fusion/eight_neighbours.h"
#include "fusion/for_rows.h"
#include "fusion/outlier_filter.h"
#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {
namespace {

bool measured(const DisplacementVector& v) { return v.flag == VectorFlag::kOk; }

// The component's central difference at (row, col), halved (change per
// node); one-sided at the grid's edge and beside unmeasured nodes, 0 where
// neither neighbour is measured.
double node_gradient(const DisplacementField& field, int row, int col, int dr, int dc, bool u) {
  auto value_at = [&](int r, int c, double& value) {
    if (r < 0 || c < 0 || r >= field.rows || c >= field.cols || !measured(field.at(r, c))) return false;
    value = u ? field.at(r, c).u_px : field.at(r, c).v_px;
    return true;
  };
  double centre = 0, before = 0, after = 0;
  value_at(row, col, centre);
  const bool has_before = value_at(row - dr, col - dc, before);
  const bool has_after = value_at(row + dr, col + dc, after);
  if (has_before && has_after) return (after - before) / 2;
  if (has_after) return after - centre;
  if (has_before) return centre - before;
  return 0;
}

// smooth_unrefined over the rows [first, last) of the grid: a Gaussian over
// (w, w·u, w·v) per node, w = 1 for the nodes averaged, filtered along each
// row and then across rows, zero beyond the grid (with the weights filtered
// alike, the edge is normalised like the rest). The band keeps only the last
// 2·half + 1 rows filtered along the row, in a ring that stays in cache;
// OpenCV's sepFilter2D needed the whole grid weighted and filtered (2 × 6 MB
// for a 16 MP frame) and has no SIMD path in double, and took 2.5 ms of a
// frame. The rows within `half` of a neighbouring band are read by it
// unsmoothed: their results wait in the band's storage until every band is
// done.
class SmoothingBand {
 public:
  SmoothingBand(DisplacementField& field, const cv::Mat& refine, const double* weights, int half,
                SmoothingBuffers::Band& storage)
      : field_(field), refine_(refine), weights_(weights), half_(half), taps_(2 * half + 1),
        width_(3 * static_cast<std::size_t>(field.cols)), storage_(storage), inputs_(static_cast<std::size_t>(taps_)) {}

  void run(int first, int last) {
    // One padded row, the ring, the row filtered across, the deferred rows.
    const std::size_t rows_kept = static_cast<std::size_t>(taps_) + 1 + 2 * static_cast<std::size_t>(half_);
    storage_.values.assign(padded_width() + rows_kept * width_, 0.0);
    storage_.deferred_rows.clear();
    double* out = ring(0) + taps_ * width_;
    for (int row = first - half_; row < first + half_; ++row) filter_along(row);
    for (int row = first; row < last; ++row) {
      filter_along(row + half_);
      for (int k = 0; k < taps_; ++k) inputs_[k] = ring(row - half_ + k);
      weighted_sum(inputs_.data(), taps_, weights_, width_, out);
      const bool read_by_neighbour = (row < first + half_ && first > 0) || (row >= last - half_ && last < field_.rows);
      if (read_by_neighbour) {
        std::copy(out, out + width_, deferred(storage_.deferred_rows.size()));
        storage_.deferred_rows.push_back(row);
      } else {
        write_back(row, out);
      }
    }
  }

  void write_back_deferred() {
    for (std::size_t i = 0; i < storage_.deferred_rows.size(); ++i) write_back(storage_.deferred_rows[i], deferred(i));
  }

 private:
  std::size_t padded_width() const { return width_ + 6 * static_cast<std::size_t>(half_); }
  double* ring(int row) {
    const int slot = ((row % taps_) + taps_) % taps_;
    return storage_.values.data() + padded_width() + static_cast<std::size_t>(slot) * width_;
  }
  double* deferred(std::size_t i) { return ring(0) + (taps_ + 1 + i) * width_; }

  // Grid row `row` weighted and filtered along the row into its ring slot.
  void filter_along(int row) {
    double* into = ring(row);
    if (row < 0 || row >= field_.rows) {
      std::fill(into, into + width_, 0.0);
      return;
    }
    double* padded = storage_.values.data();
    double* values = padded + 3 * half_;  // after 3·half zeros, and as many after the row
    const std::uint8_t* refined = refine_.ptr<std::uint8_t>(row);
    for (int col = 0; col < field_.cols; ++col) {
      const auto& vec = field_.at(row, col);
      const bool averaged = !refined[col] && measured(vec);
      values[3 * col] = averaged ? 1.0 : 0.0;
      values[3 * col + 1] = averaged ? vec.u_px : 0.0;
      values[3 * col + 2] = averaged ? vec.v_px : 0.0;
    }
    for (int k = 0; k < taps_; ++k) inputs_[k] = padded + 3 * k;
    weighted_sum(inputs_.data(), taps_, weights_, width_, into);
  }

  void write_back(int row, const double* smoothed) {
    const std::uint8_t* refined = refine_.ptr<std::uint8_t>(row);
    for (int col = 0; col < field_.cols; ++col) {
      auto& vec = field_.at(row, col);
      if (refined[col] || !measured(vec)) continue;
      const double w = smoothed[3 * col];  // ≥ the node's own weight, > 0
      vec.u_px = smoothed[3 * col + 1] / w;
      vec.v_px = smoothed[3 * col + 2] / w;
    }
  }

  DisplacementField& field_;
  const cv::Mat& refine_;
  const double* weights_;
  int half_, taps_;
  std::size_t width_;
  SmoothingBuffers::Band& storage_;
  std::vector<const double*> inputs_;
};

// Whether a component's gradient at (row, col) exceeds threshold_px along
// the row or the column.
bool gradient_exceeds(const DisplacementField& field, int row, int col, double threshold_px) {
  if (row > 0 && col > 0 && row + 1 < field.rows && col + 1 < field.cols) {
    const auto &left = field.at(row, col - 1), &right = field.at(row, col + 1);
    const auto &above = field.at(row - 1, col), &below = field.at(row + 1, col);
    if (measured(left) && measured(right) && measured(above) && measured(below)) {
      // Most nodes: central differences, as node_gradient takes them there,
      // without its tests for each neighbour.
      return std::abs((right.u_px - left.u_px) / 2) > threshold_px ||
             std::abs((below.u_px - above.u_px) / 2) > threshold_px ||
             std::abs((right.v_px - left.v_px) / 2) > threshold_px ||
             std::abs((below.v_px - above.v_px) / 2) > threshold_px;
    }
  }
  for (const bool u : {true, false}) {
    if (std::abs(node_gradient(field, row, col, 0, 1, u)) > threshold_px ||
        std::abs(node_gradient(field, row, col, 1, 0, u)) > threshold_px) {
      return true;
    }
  }
  return false;
}

}  // namespace

double field_noise_floor_px(const DisplacementField& field) {
  // Each node's two residuals in its own slots, rows in parallel, then
  // gathered in node order: the median sees what a serial loop would give it.
  std::vector<double> per_node(2 * field.vectors.size());
  std::vector<std::uint8_t> has_residual(field.vectors.size(), 0);
  for_rows(field.rows, [&](int row) {
    EightNeighbourBlock block;
    auto residuals_of_block = [&] {
      std::array<double, EightNeighbourBlock::kNodes> u, v;
      medians_of_eight(block.u.data(), block.kNodes, block.count, u.data());
      medians_of_eight(block.v.data(), block.kNodes, block.count, v.data());
      for (int j = 0; j < block.count; ++j) {
        const std::size_t i = block.index[j];
        per_node[2 * i] = std::abs(block.centre_u[j] - u[j]);
        per_node[2 * i + 1] = std::abs(block.centre_v[j] - v[j]);
        has_residual[i] = 1;
      }
      block.count = 0;
    };
    for (int col = 0; col < field.cols; ++col) {
      const auto& vec = field.at(row, col);
      if (!measured(vec)) continue;
      const bool inside = row > 0 && col > 0 && row + 1 < field.rows && col + 1 < field.cols;
      if (inside && block.add_if_all_measured(field, row, col)) {  // most nodes: many medians at once
        if (block.full()) residuals_of_block();
        continue;
      }
      Neighbours n = neighbours_of(field, row, col, measured);
      if (n.count < 3) continue;
      const std::size_t i = static_cast<std::size_t>(row) * field.cols + col;
      per_node[2 * i] = std::abs(vec.u_px - median_in_place(n.u.data(), n.count));
      per_node[2 * i + 1] = std::abs(vec.v_px - median_in_place(n.v.data(), n.count));
      has_residual[i] = 1;
    }
    if (block.count > 0) residuals_of_block();
  });
  std::vector<double> residuals;
  residuals.reserve(per_node.size());
  for (std::size_t i = 0; i < has_residual.size(); ++i) {
    if (!has_residual[i]) continue;
    residuals.push_back(per_node[2 * i]);
    residuals.push_back(per_node[2 * i + 1]);
  }
  if (residuals.size() < 16) return -1;  // 8 vectors, two components each
  const double mad = median_of_non_negative(residuals);
  return std::isfinite(mad) ? 1.4826 * mad : -1;
}

cv::Mat displaced_nodes(const DisplacementField& field, double threshold_px) {
  cv::Mat displaced = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  for_rows(field.rows, [&](int row) {
    for (int col = 0; col < field.cols; ++col) {
      const auto& vec = field.at(row, col);
      if (vec.flag == VectorFlag::kOutOfRoi) continue;
      // |d| > threshold without hypot's care for overflow (an overflowing
      // square is infinite, so still above it), which cost most of the test.
      const bool show = !measured(vec) ||
                        vec.u_px * vec.u_px + vec.v_px * vec.v_px > threshold_px * threshold_px ||
                        gradient_exceeds(field, row, col, threshold_px);
      // A NaN (which no evaluator should give) counts as displaced: refining it is safe.
      if (show || !std::isfinite(vec.u_px) || !std::isfinite(vec.v_px)) displaced.at<std::uint8_t>(row, col) = 1;
    }
  });
  return displaced;
}

RefinementSelection select_refinement(const DisplacementField& first_pass, const GridGeometry& first_grid,
                                      const DisplacementField& target, const GridGeometry& target_grid,
                                      double threshold_factor, int context_nodes) {
  if (!(threshold_factor > 0)) throw std::invalid_argument("adaptive refinement threshold factor must be positive");
  if (context_nodes < 0) throw std::invalid_argument("adaptive refinement context must be at least 0 nodes");
  if (first_pass.rows != first_grid.rows || first_pass.cols != first_grid.cols || target.rows != target_grid.rows ||
      target.cols != target_grid.cols) {
    throw std::invalid_argument("adaptive refinement: a field does not match its grid");
  }
  RefinementSelection selection;
  selection.noise_floor_px = field_noise_floor_px(first_pass);
  cv::Mat refine(target.rows, target.cols, CV_8U, cv::Scalar(1));
  if (selection.noise_floor_px >= 0 && first_pass.rows > 0 && first_pass.cols > 0) {
    selection.threshold_px = threshold_factor * selection.noise_floor_px;
    const cv::Mat displaced = displaced_nodes(first_pass, selection.threshold_px);
    // The first-pass nodes a target node is interpolated from (field_warp.h's bilinear stencil).
    auto stencil = [](double position_px, double origin_px, double step_px, int nodes) {
      const double g = std::clamp((position_px - origin_px) / step_px, 0.0, double(nodes - 1));
      const int i0 = std::min(static_cast<int>(g), nodes - 1);
      return std::pair{i0, g > i0 ? std::min(i0 + 1, nodes - 1) : i0};  // not the node of weight 0
    };
    std::vector<std::pair<int, int>> columns(static_cast<std::size_t>(target.cols));
    for (int col = 0; col < target.cols; ++col) {
      columns[static_cast<std::size_t>(col)] =
          stencil(target_grid.x0_px + col * target_grid.step_px, first_grid.x0_px, first_grid.step_px, first_grid.cols);
    }
    for_rows(target.rows, [&](int row) {
      const auto [r0, r1] =
          stencil(target_grid.y0_px + row * target_grid.step_px, first_grid.y0_px, first_grid.step_px, first_grid.rows);
      const std::uint8_t *above = displaced.ptr<std::uint8_t>(r0), *below = displaced.ptr<std::uint8_t>(r1);
      std::uint8_t* out = refine.ptr<std::uint8_t>(row);
      for (int col = 0; col < target.cols; ++col) {
        const auto [c0, c1] = columns[static_cast<std::size_t>(col)];
        out[col] = above[c0] | above[c1] | below[c0] | below[c1];
      }
    });
    if (context_nodes > 0 && !refine.empty()) {
      const cv::Mat square = cv::Mat::ones(2 * context_nodes + 1, 2 * context_nodes + 1, CV_8U);
      cv::dilate(refine, refine, square, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    }
  }
  // Counted per row on all cores, then added.
  std::vector<std::pair<std::size_t, std::size_t>> counts(static_cast<std::size_t>(target.rows));
  for_rows(target.rows, [&](int row) {
    auto& [candidates, selected] = counts[static_cast<std::size_t>(row)];
    std::uint8_t* nodes = refine.ptr<std::uint8_t>(row);
    for (int col = 0; col < target.cols; ++col) {
      if (target.at(row, col).flag == VectorFlag::kOutOfRoi) {
        nodes[col] = 0;
        continue;
      }
      ++candidates;
      selected += nodes[col];
    }
  });
  for (const auto& [candidates, selected] : counts) {
    selection.candidates += candidates;
    selection.selected += selected;
  }
  selection.refine = refine;
  return selection;
}

void smooth_unrefined(DisplacementField& field, const cv::Mat& refine, double sigma_nodes) {
  SmoothingBuffers buffers;
  smooth_unrefined(field, refine, sigma_nodes, buffers);
}

void smooth_unrefined(DisplacementField& field, const cv::Mat& refine, double sigma_nodes, SmoothingBuffers& buffers) {
  if (!(sigma_nodes >= 0) || !std::isfinite(sigma_nodes)) {
    throw std::invalid_argument("adaptive refinement smoothing must be 0 or more nodes");
  }
  if (refine.rows != field.rows || refine.cols != field.cols || refine.type() != CV_8U) {
    throw std::invalid_argument("adaptive refinement: the selection does not match the field");
  }
  if (sigma_nodes == 0 || field.vectors.empty()) return;
  const int half = static_cast<int>(std::ceil(3 * sigma_nodes));
  const cv::Mat kernel = cv::getGaussianKernel(2 * half + 1, sigma_nodes, CV_64F);
  const int bands = field.rows < 64 ? 1 : std::max(1, cv::getNumThreads());
  buffers.bands.resize(static_cast<std::size_t>(bands));
  std::vector<SmoothingBand> smoothing;
  for (auto& band : buffers.bands) smoothing.emplace_back(field, refine, kernel.ptr<double>(), half, band);
  const auto first_row = [&](int band) { return static_cast<int>(static_cast<std::int64_t>(field.rows) * band / bands); };
  cv::parallel_for_(
      cv::Range(0, bands),
      [&](const cv::Range& range) {
        for (int band = range.start; band < range.end; ++band) smoothing[band].run(first_row(band), first_row(band + 1));
      },
      bands);
  for (auto& band : smoothing) band.write_back_deferred();
}

int refinement_context_nodes(int window_px, int search_radius_px, int step_px) {
  if (step_px < 1) throw std::invalid_argument("adaptive refinement: the grid step must be at least 1 px");
  const int reach_px = window_px / 2 + search_radius_px + 4;
  return (reach_px + step_px - 1) / step_px + 2;
}

}  // namespace bosfuse::fusion
