#pragma once
// Window deformation for multipass evaluation. A field known at grid nodes
// is interpolated to every pixel (bilinear between nodes, continued
// linearly for two node steps beyond the outermost nodes and held beyond
// that), and the measurement image is resampled at
// (x + U(x,y), y + V(x,y)) so that, where the field is right, the warped
// measurement matches the reference and the next pass only measures the
// remaining (sub-pixel) error.
//
// The resampling is done here rather than with cv::remap because remap
// quantises the sub-pixel position to 1/32 px, which alone would bias BOS
// shifts by up to 0.016 px. Coordinates outside the image are clamped to its
// edge (replicated border), so a region may extend past the image.

#include <algorithm>
#include <opencv2/core.hpp>
#include <vector>

#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {

enum class Interpolator {
  kCubic,     // Keys cubic convolution (a = −0.5), 4×4 taps: fast, but biased by ~0.03 px on 3 px dots
  kLanczos3,  // windowed sinc, 6×6 taps: bias below 0.005 px on 3 px dots
  kLanczos4,  // windowed sinc, 8×8 taps: a little more accurate again, ~1.7× the cost
  // Interpolating B-splines (Unser 1999, IEEE Signal Process. Mag. 16(6):22):
  // the image is first prefiltered into its spline coefficients
  // (bspline_coefficients), which the warp then samples with the B-spline's
  // 4×4 (cubic) or 6×6 (quintic) taps. Far smaller position error than a
  // windowed sinc of the same taps (Schreier, Braasch & Sutton 2000, Opt.
  // Eng. 39:2915, for image correlation); the prefilter is one pass over the
  // measurement per frame, shared by every pass.
  kBSpline3,
  kBSpline5,  // the default
};

// Whether the warp samples the interpolator's coefficients rather than the
// image itself (the B-splines).
bool needs_coefficients(Interpolator interpolator);

// The border of replicated pixels bspline_coefficients adds on every side:
// the warp then reproduces the replicated border the other interpolators
// read past the image's edge (the prefilter's mirror boundary is this far
// out, where its influence has decayed below float resolution).
constexpr int kCoefficientBorderPx = 16;

// The interpolating B-spline coefficients for `interpolator` (a B-spline)
// of the image extended by kCoefficientBorderPx replicated pixels on every
// side, into `out` (reused when it has the size; must not be `image`): the
// recursive prefilter along rows and columns. warp_region samples them in
// the image's coordinates; at whole-pixel shifts it gives the image back
// (to float rounding). CV_32FC1 in and out.
void bspline_coefficients(const cv::Mat& image, Interpolator interpolator, cv::Mat& out);

// Nodes at x = x0_px + col·step_px, y = y0_px + row·step_px.
struct GridGeometry {
  double x0_px = 0;
  double y0_px = 0;
  double step_px = 1;
  int rows = 0;
  int cols = 0;
};

// Node values as rows×cols CV_64FC1 matrices.
struct GridField {
  GridGeometry grid;
  cv::Mat u_px;
  cv::Mat v_px;
};

// Where a point lies between the nodes along one axis: nodes i0 and i1,
// at fraction t from i0 (axis_weight: held at the outermost node beyond it,
// as interpolate_field and GridSampler use it; the warp continues the
// outermost piece, continued_axis_weight).
struct AxisWeight {
  int i0 = 0;
  int i1 = 0;
  double t = 0;
};

inline AxisWeight axis_weight(double position_px, double origin_px, double step_px, int nodes) {
  const double g = std::clamp((position_px - origin_px) / step_px, 0.0, double(nodes - 1));
  AxisWeight w;
  w.i0 = std::min(static_cast<int>(g), nodes - 1);
  w.i1 = std::min(w.i0 + 1, nodes - 1);
  w.t = g - w.i0;
  return w;
}

// The same, but up to `reach_steps` node steps beyond the outermost node
// the outermost piece continues linearly (t < 0 or t > 1), held beyond.
inline AxisWeight continued_axis_weight(double position_px, double origin_px, double step_px, int nodes,
                                        double reach_steps) {
  if (nodes < 2) return axis_weight(position_px, origin_px, step_px, nodes);
  const double g = std::clamp((position_px - origin_px) / step_px, -reach_steps, nodes - 1 + reach_steps);
  AxisWeight w;
  w.i0 = std::clamp(static_cast<int>(std::floor(g)), 0, nodes - 2);
  w.i1 = w.i0 + 1;
  w.t = g - w.i0;
  return w;
}

inline double bilinear(const cv::Mat& values, const AxisWeight& wx, const AxisWeight& wy) {
  const double* r0 = values.ptr<double>(wy.i0);
  const double* r1 = values.ptr<double>(wy.i1);
  const double top = r0[wx.i0] + wx.t * (r0[wx.i1] - r0[wx.i0]);
  const double bottom = r1[wx.i0] + wx.t * (r1[wx.i1] - r1[wx.i0]);
  return top + wy.t * (bottom - top);
}

// The field interpolated at one point.
cv::Point2d interpolate_field(const GridField& field, double x_px, double y_px);

// interpolate_field at the points (x_px[col], y_px[row]) of a grid, such as
// every node of a finer field: the same values, each column's and row's
// weights found once rather than at every point (a division and a clamp per
// axis cost more than the interpolation).
class GridSampler {
 public:
  // `field` must outlive the sampler.
  GridSampler(const GridField& field, const std::vector<double>& x_px, const std::vector<double>& y_px);
  cv::Point2d at(int row, int col) const {
    const AxisWeight& wx = columns_[static_cast<std::size_t>(col)];
    const AxisWeight& wy = rows_[static_cast<std::size_t>(row)];
    return {bilinear(field_.u_px, wx, wy), bilinear(field_.v_px, wx, wy)};
  }

 private:
  const GridField& field_;
  std::vector<AxisWeight> columns_, rows_;
};

// The nodes warp_region reads over `region` (its pixels lie between them):
// rows and columns of `grid`, inclusive. A field needs values there alone.
cv::Rect nodes_under(cv::Rect region, const GridGeometry& grid);

// The measurement resampled over `region` (in image coordinates; may extend
// past the image): result(y, x) = image(region.y + y + V, region.x + x + U).
// With an empty field (no nodes) it is a plain copy with replicated border.
// `image` is CV_32FC1; for a B-spline interpolator, its coefficients
// (bspline_coefficients; an empty field copies `image` as it is). Uses all
// threads. The taps are summed by the SIMD kernel sample_separable
// (fusion/simd_kernels.h).
cv::Mat warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator);

// The same into `out`, whose buffer is reused when it has the region's size
// already (passes and frames of one evaluation warp into one buffer). `out`
// may be a view into a larger buffer of that size; it must not share pixels
// with `image`.
void warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator,
                 cv::Mat& out);

// The reference for warp_region: the same positions and weights, the taps
// summed by scalar_sample_separable. The two differ only by float rounding.
cv::Mat scalar_warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator);

// The interpolator's weights as warp_region uses them (tabulated; static
// storage, valid for the life of the program).
TabulatedKernel interpolation_kernel(Interpolator interpolator);

}  // namespace bosfuse::fusion
