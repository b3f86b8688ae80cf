#pragma once
// The standard uncertainty of one cross-correlation vector, σu and σv in px,
// by correlation statistics (Wieneke 2015, Meas. Sci. Technol. 26 074002).
// Use it on the windows the final pass correlated — the reference window a
// and the (deformed) measurement window b at the correlation's integer peak
// — after the sub-pixel fit: what the two windows do not share (sensor
// noise, interpolation error, a gradient inside the window, a brightness
// change) is what moves the peak, and it shows in them.
//
// With a', b' the windows less their means, the correlation's neighbours of
// the peak along x are C+ = Σ a'(i)·b'(i+1) and C− = Σ a'(i+1)·b'(i): two
// sums of the same products but for the mismatch, so for identical windows
// each pixel's contribution ΔC_i = a'(i)·b'(i+1) − a'(i+1)·b'(i) to C+ − C−
// is 0. Their spread σ_ΔC is the uncertainty of C+ − C−, and the 3-point
// Gaussian fit turns it into px:
//
//   σx = ln((C± + σ_ΔC/2) / (C± − σ_ΔC/2)) / (2·ln(C0² / ((C± + σ_ΔC/2)(C± − σ_ΔC/2))))
//
// with C± = (C+ + C−)/2 and C0 = Σ a'·b' (C± sum over n − 1 of the n
// columns, C0 is scaled to as many), and σ_ΔC² the variance of Σ ΔC_i.
// Likewise along y. The sums are simd_kernels.h's
// correlation_statistics_sums and correlation_lag_sums (float lanes per
// column, added in double).
//
// The paper takes σ_ΔC² = Σ (ΔC_i − mean ΔC)², as if the contributions were
// independent. They are not: noise in pixel k of b enters ΔC_(k−1) with
// a'(k−1) and ΔC_k with −a'(k+1), and the warp's mismatch of the signal
// (the deformed b is the B-spline's interpolation of the measurement, not
// the shifted scene) is a function of the texture spread over the
// interpolator's taps, whose contributions largely cancel in the sum: on
// noiseless pairs at fractional shifts the per-pixel sum gave σ 1.6 × the
// error. σ_ΔC² here is the variance of the sum estimated from the
// contributions themselves, Σ d_i² + 2 Σ_(l=1…L) Σ d_i·d_(i+l) along the
// axis (d the contributions less their mean; a truncated-kernel estimate
// of the variance of a sum of correlated terms), L = kContributionLags = 2:
// the coverage of every synthetic case is the same within 1 point for L =
// 2, 3, 4 (the correlation has ended), and L = 1 leaves the mismatch's
// lag-2 correlation out (uniform shifts 82 %). For independent pixel noise
// it is what the former factor 1 − ρ(2 px) of the reference window gave
// (MatchesTheScatterOfNoisyWindows). A mismatch that is no such noise — a
// window whose deformed samples reach past the image, where the warp
// replicates its border pixels — keeps the per-pixel sum
// (`correlated_contributions` false), which is the larger.
//
// Nor in the windows: the predictor. The final pass measures
// p + W[field − P(p)], P the bilinear deformation of the predictor p and W
// the window's average; W∘P is a fixed filter K of the node values (the
// binomial [¼ ½ ¼]² for windows of two node steps), and p is the earlier
// pass's vectors, smoothed (S), measured on the same images at the same
// nodes: the same error n the final windows show. The vector therefore
// carries F = δ + (δ − K)·S times n, and σ is scaled by √ΣF²
// (predictor_noise_gain: 1.113 for the defaults, 1.772 unsmoothed; the
// neighbours taken as independent). Measured at zero shift: 1.13 and 1.82
// (DISABLED_PredictorNoiseAtZeroShift). It assumes the earlier pass had
// the final pass's windows (first_window_px = window_px, the default).
//
// What it covers: what the final windows show. Not in them: what the
// deformation did not follow. At the grid's outermost nodes the predictor
// was smoothed over a one-sided neighbourhood and the deformation is held
// constant beyond the node, and in a displacement gradient the vector there
// keeps part of that offset (0.037 px at 1 px over λ 128 px, against
// 0.01 px inside): add_held_deformation_uncertainty adds, in quadrature, the
// size of the correction the final pass made to that node's predictor. The
// evaluator's spatial response to strong curvature inside the field is not
// modelled as such; on the steep sinusoids of docs/UNCERTAINTY.md σ covers
// it with the two corrections above.
//
// The moment-of-correlation method (Bhattacharya et al. 2018) is the other
// established estimator; it reads the correlation plane's peak shape and
// maps it to σ through a curve fitted to simulated pairs. It has not been
// compared here; this one needs only the two windows and no fitted curve.
//
// A vector whose peak cannot resolve its own uncertainty (C± − σ_ΔC/2 ≤ 0,
// or the peak no higher than its shifted neighbours) gets kUnresolvedPx, the
// width the sub-pixel fit is bounded to; none gets less than kFloorPx.

#include <opencv2/core.hpp>

#include "fusion/displacement_field.h"
#include "fusion/field_warp.h"

namespace bosfuse::fusion {

struct VectorUncertainty {
  double sigma_u_px = 0;
  double sigma_v_px = 0;
};

inline constexpr double kUnresolvedPx = 1.0;
// The least σ reported: far below any camera's noise, above 0, which a
// DisplacementVector keeps for "not estimated".
inline constexpr double kFloorPx = 1e-4;

// The lags along each axis whose products enter σ_ΔC² (see above; the
// kernel sums lags 1 and 2).
inline constexpr int kContributionLags = 2;

// `reference_window` and `measurement_window` are n×n CV_32FC1 (views into
// larger images are fine), n ≥ 4; the measurement window is the one at the
// correlation's integer peak. `correlated_contributions` false: the
// per-pixel sum as it is (a mismatch that is not independent pixel noise
// nor the warp's, see above).
VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window,
                                          bool correlated_contributions = true);

// √ΣF² of the predictor's noise carried into the final pass's vector (see
// above), for windows of `window_px`, nodes `step_px` apart and the
// predictor smoothed by the 3×3 binomial or not.
double predictor_noise_gain(int window_px, int step_px, bool smoothed_predictor);

// `sigma` × `gain`, within [kFloorPx, kUnresolvedPx]; kUnresolvedPx stays.
VectorUncertainty with_predictor_noise(const VectorUncertainty& sigma, double gain);

// The 3-point Gaussian fit's standard uncertainty along one axis, from the
// correlation at the peak (c0), the mean of its two neighbours (c_pm) and
// the standard uncertainty of their difference (sigma_delta): Wieneke's
// formula above; kUnresolvedPx where it has no answer.
double gaussian_peak_uncertainty(double c0, double c_pm, double sigma_delta);

// At the outermost rows and columns of `field` (measured vectors with a σ
// only, and under `only` the nodes marked non-zero there, CV_8U of the
// field's shape), σu² += (u − predictor u)², likewise v: the correction the
// final pass made to a deformation that was held constant beyond the node
// and smoothed one-sidedly, of the size of what it left (see above).
// `predictor` is the final pass's deformation on the field's grid.
void add_held_deformation_uncertainty(const GridField& predictor, DisplacementField& field,
                                      const cv::Mat* only = nullptr);

}  // namespace bosfuse::fusion
