#pragma once
// for_rows(rows, body) calls body(row) for every row of a grid of nodes,
// the rows of a large grid on all cores. Use it for per-node work over a
// displacement field (outlier test, predictor, adaptive selection) whose
// work for a row writes only that row: a 16 MP frame's field has 250,000
// nodes, and a serial loop over it is time the other core idles. A grid of
// fewer than 64 rows (a probe's) runs on the calling thread, which costs
// less than waking another.

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <opencv2/core/utility.hpp>

namespace bosfuse::fusion {

template <typename Body>
void for_rows(int rows, Body body) {
  auto range = [&](const cv::Range& r) {
    for (int row = r.start; row < r.end; ++row) body(row);
  };
  if (rows < 64) {
    range(cv::Range(0, rows));
  } else {
    cv::parallel_for_(cv::Range(0, rows), range);
  }
}

// for_marked_runs(mask, body) calls body(row, first, last) for every run
// of nodes [first, last) of a row that `mask` (CV_8U, the grid's rows×cols)
// marks non-zero, rows as for_rows spreads them: the work adaptive
// refinement restricts to its selection, which lies in runs (a plume, the
// tiles of a warp), so a run's loop can copy or vectorise.
template <typename Body>
void for_marked_runs(const cv::Mat& mask, Body body) {
  for_rows(mask.rows, [&](int row) {
    const std::uint8_t* marked = mask.ptr<std::uint8_t>(row);
    for (int col = 0; col < mask.cols;) {
      if (!marked[col]) {
        ++col;
        continue;
      }
      const int first = col;
      while (col < mask.cols && marked[col]) ++col;
      body(row, first, col);
    }
  });
}

// for_marked(mask, body) calls body(row, col) for every node that `mask` marks.
template <typename Body>
void for_marked(const cv::Mat& mask, Body body) {
  for_marked_runs(mask, [&](int row, int first, int last) {
    for (int col = first; col < last; ++col) body(row, col);
  });
}

}  // namespace bosfuse::fusion
