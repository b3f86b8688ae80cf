#pragma once
// Sub-pixel location of a correlation peak from the 3×3 values around its
// integer maximum. Three estimators:
//  - kGaussian3Point fits a Gaussian through three points along x and along
//    y separately: the PIV standard, exact for a Gaussian peak aligned with
//    the axes, but with peak locking (a bias towards integer shifts) when the
//    peak is not Gaussian;
//  - kGaussian2dFit fits ln c = a0 + a1 x + a2 y + a3 x² + a4 xy + a5 y² to
//    all nine values by least squares (Nobach & Honkanen 2005), which uses the
//    diagonal information, tolerates elliptic/tilted peaks and locks less;
//  - kParabola3Point fits a parabola through the same three points along
//    each axis. At a residual near 0 (after window deformation) it is less
//    sensitive to noise in the neighbours than the Gaussian — for a peak of
//    σ 1 px by q·|ln q| / (1 − q) = 0.77, q = c(±1)/c(0) — at the cost of
//    more bias away from 0. What OpenPIV's default does in effect: its
//    correlation of windows whose mean is not removed stands on a pedestal,
//    where the logarithm of its Gaussian fit is nearly linear.
// Values must come from a zero-normalised correlation (≤ 1); non-positive
// values are clamped to a small positive floor so the logarithm is finite.
// The result is bounded to ±1 px; an estimator that fails (no maximum in the
// fitted surface) returns the 3-point result, and that in turn 0.

#include <array>

namespace bosfuse::fusion {

enum class SubpixelEstimator { kGaussian3Point, kGaussian2dFit, kParabola3Point };

struct SubpixelOffset {
  double dx_px = 0;
  double dy_px = 0;
};

// `c` is row-major: c[0..2] is the row above the peak, c[4] the peak.
SubpixelOffset subpixel_offset(const std::array<double, 9>& c, SubpixelEstimator estimator);

// Along one axis: values left, centre, right.
double gaussian_3point(double left, double centre, double right);
double parabola_3point(double left, double centre, double right);

}  // namespace bosfuse::fusion
