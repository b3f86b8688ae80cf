#pragma once
// Normalized median test (Westerweel & Scarano 2005) for a gridded field: a
// vector is an outlier when its distance from the median of its (up to 8)
// measured neighbours, divided by the median of the neighbours' own
// distances from that median plus ε, exceeds a threshold. ε (0.1 px)
// accounts for the noise floor of cross-correlation, so a smooth field is not
// torn apart by tiny residuals. Outliers are replaced by the median of their
// measured neighbours and flagged; the test is applied to a snapshot, so the
// result does not depend on the order the grid is visited.
//
// fill_unmeasured then gives every vector that was not measured (no peak,
// masked, no texture) a value from its neighbours — only for use as the
// predictor of the next pass, so deformation near a gap is not dragged to 0.

#include <span>
#include <string>

#include "fusion/displacement_field.h"
#include "fusion/field_warp.h"

namespace bosfuse::fusion {

struct OutlierOptions {
  double threshold = 2.0;
  double epsilon_px = 0.1;
  int min_neighbours = 3;  // fewer measured neighbours: no verdict, the vector stays
  // Nodes on the grid's outer edge have all their neighbours on one side: in
  // a gradient that one-sided median is off by a whole grid step's change,
  // and the test would "replace" good vectors with wrong ones (40 of 124 edge
  // vectors of a 1 px sinusoid). Off by default.
  bool test_grid_edges = false;

  std::string Validate() const;  // empty when valid
};

// The median of values[0 … count) (the mean of the middle two for an even
// count), reordering them; NaN for none. Eight values, a node's neighbours,
// by a sorting network, fewer by insertion, more by nth_element.
double median_in_place(double* values, int count);

// The median of values that are none of them negative (NaN for none),
// equal to median_in_place's, for many values: a noise floor's 125,000
// residuals, where nth_element took 1.2 ms of a 16 MP frame's 100 under
// adaptive refinement. Such values' bit patterns, read as unsigned integers,
// order as the values do: a histogram of their top 16 bits finds the bucket
// holding each middle rank, and only that bucket's values are ordered.
double median_of_non_negative(std::span<const double> values);

// Tests vectors flagged kOk; returns how many were replaced. With `only`
// (CV_8U, the field's rows×cols) just the nodes marked non-zero there are
// tested and replaced. A test and a replacement read the node's neighbours
// as the whole field's test does, so a node whose 3×3 neighbourhood is all
// marked ends as the whole field's test would leave it. With `replace_in`
// (the same shape) only the outliers it marks are replaced; the others are
// left as they are, but still count as outliers where a replacement is taken
// from the neighbours (adaptive refinement tests the ring around its
// selection for that, and keeps the ring's first-pass values).
std::size_t replace_outliers(DisplacementField& field, const OutlierOptions& options, const cv::Mat* only = nullptr,
                             const cv::Mat* replace_in = nullptr);

// σu, σv of each vector replace_outliers replaced (kOutlierReplaced), once
// its neighbours' σ are known: the replacement is the median of its measured
// neighbours, so its error is how far the field at the node lies from them
// (their robust spread, 1.4826 × the median absolute deviation of their u
// and of their v, which holds their noise and the field's change across
// the node) together with one neighbour's own error (their median σ), in
// quadrature: σ² = spread² + median(σ)². With `only` (CV_8U, the field's
// shape) only the nodes marked there. Unmeasured vectors keep σ = 0.
void estimate_replaced_uncertainty(DisplacementField& field, const cv::Mat* only = nullptr);

// The predictor for the next pass on `grid` (the field's own grid):
// measured and replaced vectors as they are; every other node the median of
// its already-filled neighbours, spreading outwards for at most `max_sweeps`
// sweeps, and 0 where nothing reaches.
GridField predictor_from(const DisplacementField& field, const GridGeometry& grid, int max_sweeps = 32);
// The same into `predictor`, whose buffers are reused when they have the
// field's size (a 16 MP field's predictor is 4 MB, page-faulted anew when
// allocated for every pass of every frame); they are written in place, so
// no other cv::Mat may share them.
void predictor_from(const DisplacementField& field, const GridGeometry& grid, GridField& predictor,
                    int max_sweeps = 32);
// The predictor at the nodes `only` marks (CV_8U, the field's rows×cols)
// when each of them has a value (measured or replaced): then no gap is
// filled and each holds its own vector's value, as in the whole field's
// predictor; the other nodes keep what the buffers held. False when one of
// them has none: then the marked nodes hold nothing of use, and the caller
// takes predictor_from (one pass over them, not a test and then a copy).
bool predictor_at(const DisplacementField& field, const GridGeometry& grid, GridField& predictor, const cv::Mat& only);

// Smooths a predictor with the 3×3 binomial kernel (weights 1-2-1 in x and y;
// at the grid's outermost nodes the one-sided (3, 2, −1)/4 along the edge's
// normal, which keeps a linear field as it is). Iterated window deformation is unstable
// for errors at the grid's Nyquist wavelength — each pass would amplify them
// (Schrijer & Scarano 2008) — and this kernel removes exactly that component.
void smooth_predictor(GridField& predictor);
// The same, working in `scratch` (reused when it has the predictor's size),
// which afterwards holds a buffer of the predictor's old values; with
// `only`, at the nodes it marks alone (the nodes mark_smoothing_taps gives
// for them must hold the predictor), the others left as `scratch` held them.
void smooth_predictor(GridField& predictor, cv::Mat& scratch, const cv::Mat* only = nullptr);

// The nodes smooth_predictor reads for the nodes `nodes` marks (CV_8U):
// their 3×3 neighbours, and at the grid's edge the second node inwards.
void mark_smoothing_taps(const cv::Mat& nodes, cv::Mat& taps);

}  // namespace bosfuse::fusion
