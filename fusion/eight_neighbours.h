#pragma once
// A node's neighbours in a displacement field, for the median tests of the
// outlier filter and of adaptive refinement's noise floor: most nodes, whose
// eight neighbours are all measured, gathered a block at a time for the
// vector median kernels (simd_kernels.h: medians_of_eight,
// normalised_residuals_of_eight); nodes on the grid's edge or beside an
// unmeasured one one at a time (neighbours_of).

#include <array>
#include <cstddef>

#include "fusion/displacement_field.h"

namespace bosfuse::fusion {

// The values of a node's neighbours (up to 8, row by row) that `accept`
// takes.
struct Neighbours {
  std::array<double, 8> u{};
  std::array<double, 8> v{};
  int count = 0;
};

template <typename Accept>
Neighbours neighbours_of(const DisplacementField& field, int row, int col, Accept accept) {
  Neighbours n;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      const int r = row + dr, c = col + dc;
      if ((dr == 0 && dc == 0) || r < 0 || c < 0 || r >= field.rows || c >= field.cols) continue;
      const auto& vec = field.at(r, c);
      if (!accept(vec)) continue;
      n.u[n.count] = vec.u_px;
      n.v[n.count] = vec.v_px;
      ++n.count;
    }
  }
  return n;
}

// Position k of node j's neighbours at u[k·kNodes + j] (v alike).
struct EightNeighbourBlock {
  static constexpr int kNodes = 64;
  std::array<double, 8 * kNodes> u, v;
  std::array<double, kNodes> centre_u, centre_v;
  std::array<std::size_t, kNodes> index;
  int count = 0;
  // Adds the node at (row, col), inside the grid, when its eight
  // neighbours are all measured (kOk); false when they are not.
  bool add_if_all_measured(const DisplacementField& field, int row, int col) {
    const DisplacementVector* around[8] = {&field.at(row - 1, col - 1), &field.at(row - 1, col),
                                           &field.at(row - 1, col + 1), &field.at(row, col - 1),
                                           &field.at(row, col + 1),     &field.at(row + 1, col - 1),
                                           &field.at(row + 1, col),     &field.at(row + 1, col + 1)};
    bool all = true;
    for (const DisplacementVector* vec : around) all = all && vec->flag == VectorFlag::kOk;
    if (!all) return false;
    for (int k = 0; k < 8; ++k) {
      u[k * kNodes + count] = around[k]->u_px;
      v[k * kNodes + count] = around[k]->v_px;
    }
    const DisplacementVector& centre = field.at(row, col);
    centre_u[count] = centre.u_px;
    centre_v[count] = centre.v_px;
    index[count] = static_cast<std::size_t>(row) * field.cols + col;
    ++count;
    return true;
  }
  bool full() const { return count == kNodes; }
};

}  // namespace bosfuse::fusion
