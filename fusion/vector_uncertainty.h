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
// columns, C0 is scaled to as many), and σ_ΔC² = Σ (ΔC_i − mean ΔC)², the
// paper's estimate. Likewise along y. Sums over a window's pixels run in
// double.
//
// What it covers: on two windows with independent noise the fit's scatter
// (a Monte Carlo of 400 noise draws in the test
// MatchesTheScatterOfNoisyWindows: σ within 7 % of it, 95–96 % coverage). Over a whole
// multipass field it sees only what the final windows show: the error the
// earlier passes leave in the predictor, and the spatial-response bias of a
// curved field, are not in them. The per-pixel sum neglects the correlation
// of neighbouring contributions (noise in one pixel of b enters two of
// them), which overstates σ by 1/(1 − ρ(2 px)) of the pattern's
// autocorrelation ρ, and on the multipass fields measured here that about
// offsets what the final windows do not show (docs/BENCHMARKS.md,
// "Per-vector uncertainty"); the lag-corrected sum, exact for the windows
// alone, gave 0.8× the fields' errors.
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

namespace bosfuse::fusion {

struct VectorUncertainty {
  double sigma_u_px = 0;
  double sigma_v_px = 0;
};

inline constexpr double kUnresolvedPx = 1.0;
// The least σ reported: far below any camera's noise, above 0, which a
// DisplacementVector keeps for "not estimated".
inline constexpr double kFloorPx = 1e-4;

// `reference_window` and `measurement_window` are n×n CV_32FC1 (views into
// larger images are fine), n ≥ 4; the measurement window is the one at the
// correlation's integer peak.
VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window);

// The 3-point Gaussian fit's standard uncertainty along one axis, from the
// correlation at the peak (c0), the mean of its two neighbours (c_pm) and
// the standard uncertainty of their difference (sigma_delta): Wieneke's
// formula above; kUnresolvedPx where it has no answer.
double gaussian_peak_uncertainty(double c0, double c_pm, double sigma_delta);

}  // namespace bosfuse::fusion
