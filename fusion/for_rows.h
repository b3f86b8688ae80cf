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

// for_runs(marked, count, body) calls body(first, last) for every run
// [first, last) of non-zero entries of marked[0, count), in order, on the
// calling thread.
template <typename Body>
void for_runs(const std::uint8_t* marked, int count, Body body) {
  for (int i = 0; i < count;) {
    if (!marked[i]) {
      ++i;
      continue;
    }
    const int first = i;
    while (i < count && marked[i]) ++i;
    body(first, i);
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
    for_runs(mask.ptr<std::uint8_t>(row), mask.cols, [&](int first, int last) { body(row, first, last); });
  });
}

// for_row_runs(rows, cols, only, body): body(row, first, last) for the runs
// `only` marks (for_marked_runs), or for every whole row [0, cols) of a
// rows×cols grid when `only` is null: work a mask may restrict.
template <typename Body>
void for_row_runs(int rows, int cols, const cv::Mat* only, Body body) {
  if (only) {
    for_marked_runs(*only, body);
  } else {
    for_rows(rows, [&](int row) { body(row, 0, cols); });
  }
}

// for_marked(mask, body) calls body(row, col) for every node that `mask` marks.
template <typename Body>
void for_marked(const cv::Mat& mask, Body body) {
  for_marked_runs(mask, [&](int row, int first, int last) {
    for (int col = first; col < last; ++col) body(row, col);
  });
}

}  // namespace bosfuse::fusion
