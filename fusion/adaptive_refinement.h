#pragma once
// Adaptive refinement: which grid nodes the refinement passes (2…n) of a
// multipass cross-correlation need to evaluate. A BOS plume usually fills a
// fifth of the frame; the rest is background at zero displacement, where
// refinement only measures that zero again, at the cost of the plume's. Use
// it (XcorrOptions::adaptive_refinement) on scenes whose displacement is
// local; on a scene displaced everywhere it selects every node and costs only
// the selection.
//
// Noise floor. Estimated from the first pass's own vectors: the robust spread
// (1.4826 × the median absolute value) of each measured vector's residual
// against the median of its measured neighbours, u and v pooled. This is the
// figure that matters here — how far a first-pass vector scatters — and it
// includes everything that makes it scatter (sensor noise, dot size and
// density, window size, peak locking), where an estimate from the image noise
// alone would need a model of the correlation for each (on 3 px dots at IW 16
// the pattern dominates: 0.038 px without sensor noise, 0.041 px with 3 %).
// Against the neighbours' median a smooth field (a linear gradient, a plume)
// leaves only the noise, so the estimate holds however much of the frame is
// displaced, and the median ignores outliers. The residual's spread is a
// little above a single vector's (by about 10 % for independent neighbours),
// which errs on the side of refining less only by that much.
//
// Selection. A node of the first pass is "displaced" when |d| or its local
// gradient (the central difference, per grid node) exceeds threshold_factor ×
// noise floor, or when the first pass did not measure it cleanly (no peak,
// outlier, no texture, masked: refinement, with its neighbours' predictor,
// measures or flags it properly). On the refinement grid a node is selected
// when a displaced first-pass node is among the (up to 4) it is interpolated
// from, and the selection is dilated by `context_nodes`, so the deformation
// and the outlier test of every selected node see refined neighbours. A field
// whose noise floor cannot be estimated (fewer than 8 measured vectors with 3
// measured neighbours) selects every node.
//
// The nodes left out. The first pass is 2–4× noisier than refinement even
// where nothing moves (0.026 against 0.008 px RMS at IW 16, 1 % noise: its
// wide search and 2-D fit against refinement's equal windows), so copying it
// would trade the time saved for background noise. But there, by selection,
// nothing exceeds the noise floor — no structure the first pass could resolve
// — and smooth_unrefined averages the first pass over the unrefined nodes
// around each (Gaussian, σ = 2 nodes), which brings it below refinement's
// noise without taking a value across into the refined region. The price: a
// feature too weak to be selected is blurred over those 2 nodes.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fusion/displacement_field.h"
#include "fusion/field_warp.h"

namespace bosfuse::fusion {

// 1.4826 × median |residual against the neighbours' median| of the measured
// vectors with at least 3 measured neighbours; -1 when fewer than 8 such
// vectors exist.
double field_noise_floor_px(const DisplacementField& field);

// CV_8U, rows×cols of `field`: 1 where |d| or the central-difference
// gradient (px per node) exceeds threshold_px, or the vector was not measured
// cleanly (any flag but kOk and kOutOfRoi).
cv::Mat displaced_nodes(const DisplacementField& field, double threshold_px);

struct RefinementSelection {
  cv::Mat refine;              // CV_8U on the refinement grid: 1 = evaluate in passes ≥ 2
  double noise_floor_px = -1;  // of the first pass; -1: not estimable (everything selected)
  double threshold_px = 0;     // threshold_factor × noise floor
  std::size_t selected = 0;    // nodes selected (out-of-ROI nodes never are)
  std::size_t candidates = 0;  // nodes not out of the ROI
  double fraction() const { return candidates ? double(selected) / double(candidates) : 0.0; }
};

// The nodes of `target` (on `target_grid`) the refinement passes evaluate,
// from the first pass's measured vectors `first_pass` on `first_grid` (the
// same grid, or the coarse one of a coarse first pass). threshold_factor > 0,
// context_nodes ≥ 0.
RefinementSelection select_refinement(const DisplacementField& first_pass, const GridGeometry& first_grid,
                                      const DisplacementField& target, const GridGeometry& target_grid,
                                      double threshold_factor, int context_nodes);

// Replaces each measured (kOk) unrefined node's value by the mean of the
// measured unrefined nodes around it, Gaussian-weighted with sigma_nodes
// (normalised over the nodes that take part); refined and unmeasured nodes
// are left alone. sigma_nodes 0 leaves everything.
void smooth_unrefined(DisplacementField& field, const cv::Mat& refine, double sigma_nodes);

// What smooth_unrefined works in, per band of rows (one band per core):
// kept by a caller that smooths every frame, not allocated anew each time.
struct SmoothingBuffers {
  struct Band {
    std::vector<double> values;
    std::vector<int> deferred_rows;
  };
  std::vector<Band> bands;
};
void smooth_unrefined(DisplacementField& field, const cv::Mat& refine, double sigma_nodes, SmoothingBuffers& buffers);

// How many nodes around a refined one its value depends on in a pass: its
// window, search and interpolation kernel reach ceil((window/2 + search +
// 4) / step) nodes of the predictor, the predictor's smoothing one more and
// the outlier test one more.
int refinement_context_nodes(int window_px, int search_radius_px, int step_px);

}  // namespace bosfuse::fusion
