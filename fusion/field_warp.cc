#include "fusion/field_warp.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core/utility.hpp>

#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {
namespace {

void keys_weights(double t, double* w) {
  w[0] = ((-0.5 * t + 1.0) * t - 0.5) * t;
  w[1] = (1.5 * t - 2.5) * t * t + 1.0;
  w[2] = ((-1.5 * t + 2.0) * t + 0.5) * t;
  w[3] = (0.5 * t - 0.5) * t * t;
}

// Windowed sinc with `a` lobes: taps at −(a−1)..a around floor(x).
void lanczos_weights(double t, int a, double* w) {
  double total = 0;
  for (int k = 0; k < 2 * a; ++k) {
    const double x = t - (k - (a - 1));
    double value = 1.0;
    if (std::abs(x) > 1e-12) {
      const double px = std::numbers::pi * x;
      value = a * std::sin(px) * std::sin(px / a) / (px * px);
    }
    w[k] = value;
    total += value;
  }
  for (int k = 0; k < 2 * a; ++k) w[k] /= total;  // exact reproduction of a constant
}

// The centred B-spline of degree n at x: (1/n!) Σ_k (−1)^k C(n+1, k) (x + (n+1)/2 − k)^n, the powers of positive parts.
double bspline(int n, double x) {
  double sum = 0, binomial = 1, factorial = 1;
  for (int i = 2; i <= n; ++i) factorial *= i;
  for (int k = 0; k <= n + 1; ++k) {
    const double p = x + (n + 1) / 2.0 - k;
    if (p > 0) sum += ((k % 2) ? -1 : 1) * binomial * std::pow(p, n);
    binomial = binomial * (n + 1 - k) / (k + 1);
  }
  return sum / factorial;
}

// Degree-n B-spline taps at −(n−1)/2..(n+1)/2 around floor(x) (n odd).
void bspline_weights(double t, int n, double* w) {
  const int first = -(n - 1) / 2;
  for (int k = 0; k <= n; ++k) w[k] = bspline(n, t - (first + k));
}

int taps_of(Interpolator interpolator) {
  switch (interpolator) {
    case Interpolator::kCubic:
    case Interpolator::kBSpline3:
      return 4;
    case Interpolator::kLanczos3:
    case Interpolator::kBSpline5:
      return 6;
    case Interpolator::kLanczos4:
      return 8;
  }
  return 4;
}

// The poles of the interpolating B-spline's prefilter (Unser 1999, table I).
std::vector<double> prefilter_poles(Interpolator interpolator) {
  if (interpolator == Interpolator::kBSpline3) return {std::sqrt(3.0) - 2};
  return {-0.430575347099973791, -0.0430962882032647400};
}

// `count` neighbouring lines of n samples each (sample i of line j at
// s[i·count + j]) filtered in place by the prefilter's poles, with mirror
// boundaries (Unser, Aldroubi & Eden 1993). The lines side by side, so the
// recursion, serial along a line, runs in SIMD lanes across lines. In
// double: a flat image's coefficients are then exactly flat in float (a
// float recursion leaves rounding ripples that correlate as texture).
void prefilter_lines(double* s, int n, int count, const std::vector<double>& poles) {
  if (n < 2) return;
  double gain = 1;
  for (const double z : poles) gain *= (1 - z) * (1 - 1 / z);
  const auto at = [&](int i) { return s + static_cast<std::size_t>(i) * count; };
  const double g = gain;
  for (std::size_t k = 0; k < static_cast<std::size_t>(n) * count; ++k) s[k] *= g;
  std::vector<double> first(static_cast<std::size_t>(count));
  for (const double pole : poles) {
    const double z = pole;
    // The causal filter's first value: the mirrored line's sum, as far as z^k matters in float.
    const int horizon = std::min(n, static_cast<int>(std::ceil(std::log(1e-9) / std::log(std::abs(pole)))));
    std::fill(first.begin(), first.end(), 0.0);
    double zk = 1;
    for (int k = 0; k < horizon; ++k, zk *= z) {
      const double* line = at(k);
      for (int j = 0; j < count; ++j) first[j] += zk * line[j];
    }
    std::copy(first.begin(), first.end(), at(0));
    for (int i = 1; i < n; ++i) {
      double* here = at(i);
      const double* before = at(i - 1);
      for (int j = 0; j < count; ++j) here[j] += z * before[j];
    }
    const double end = pole / (pole * pole - 1);
    for (int j = 0; j < count; ++j) at(n - 1)[j] = end * (at(n - 1)[j] + z * at(n - 2)[j]);
    for (int i = n - 2; i >= 0; --i) {
      double* here = at(i);
      const double* after = at(i + 1);
      for (int j = 0; j < count; ++j) here[j] = z * (after[j] - here[j]);
    }
  }
}

// Kernel weights tabulated over the sub-pixel position t ∈ [0, 1] and
// interpolated linearly between entries (see TabulatedKernel): the
// positional error of the table (< 1e-6 px) is far below anything
// measurable, and it avoids three trigonometric calls per pixel and axis.
class WeightTable {
 public:
  static constexpr int kSteps = 1024;

  explicit WeightTable(Interpolator interpolator) : taps_(taps_of(interpolator)) {
    // Zeros after the last entry, which vector loads may read.
    table_.resize(static_cast<std::size_t>(kSteps + 1) * taps_ + 8);
    for (int i = 0; i <= kSteps; ++i) {
      double w[8] = {};
      if (interpolator == Interpolator::kCubic) {
        keys_weights(double(i) / kSteps, w);
      } else if (needs_coefficients(interpolator)) {
        bspline_weights(double(i) / kSteps, taps_ - 1, w);
      } else {
        lanczos_weights(double(i) / kSteps, taps_ / 2, w);
      }
      for (int k = 0; k < taps_; ++k) table_[static_cast<std::size_t>(i) * taps_ + k] = static_cast<float>(w[k]);
    }
  }

  TabulatedKernel kernel() const { return {table_.data(), taps_, kSteps}; }

 private:
  int taps_;
  std::vector<float> table_;
};

const WeightTable& table_of(Interpolator interpolator) {
  static const WeightTable cubic(Interpolator::kCubic), lanczos3(Interpolator::kLanczos3),
      lanczos4(Interpolator::kLanczos4), bspline3(Interpolator::kBSpline3), bspline5(Interpolator::kBSpline5);
  switch (interpolator) {
    case Interpolator::kCubic:
      return cubic;
    case Interpolator::kLanczos3:
      return lanczos3;
    case Interpolator::kLanczos4:
      return lanczos4;
    case Interpolator::kBSpline3:
      return bspline3;
    case Interpolator::kBSpline5:
      return bspline5;
  }
  return lanczos3;
}

// The columns of a region between the same two node columns: along a row
// the field there is one linear piece, u0 + t·(u1 − u0).
struct ColumnRun {
  int begin = 0, end = 0;  // columns of the region
  int i0 = 0, i1 = 0;      // node columns
};

// Each column's position in the image and its weight t between its node
// columns, as contiguous arrays so that the per-pixel loop vectorises.
struct RegionColumns {
  std::vector<double> x_px, t;
  std::vector<ColumnRun> runs;
};

// How far past the outermost node the deformation continues linearly, in
// node steps. A window centred on the outermost node reaches half a window
// past it: one step at the evaluator's default (IW 16, step 8), two at 75 %
// overlap. Held there, the window's outer half sees the field's gradient as
// a residual, which biased the outermost vectors by ~0.06 px on a 1 px
// sinusoid of λ 128 px (notes: edge.md). Beyond that nothing supports a
// trend: held.
constexpr double kContinuedSteps = 2.0;

RegionColumns region_columns(cv::Rect region, const GridGeometry& g) {
  RegionColumns columns;
  const auto width = static_cast<std::size_t>(region.width);
  columns.x_px.resize(width);
  columns.t.resize(width);
  for (int x = 0; x < region.width; ++x) {
    const AxisWeight w = continued_axis_weight(region.x + x, g.x0_px, g.step_px, g.cols, kContinuedSteps);
    columns.x_px[x] = region.x + x;
    columns.t[x] = w.t;
    if (columns.runs.empty() || columns.runs.back().i0 != w.i0 || columns.runs.back().i1 != w.i1) {
      columns.runs.push_back({x, x, w.i0, w.i1});
    }
    columns.runs.back().end = x + 1;
  }
  return columns;
}

// Rows `rows` of the warped region; most of a deformation pass's cost: the
// field at each pixel here, the resampling in sample_separable (or, with
// `simd` false, its scalar reference). The field is interpolated between
// the two node rows around a pixel row once per row (`u_row`, `v_row`, one
// value per node column), then along the row per pixel: the same bilinear
// value as `bilinear`, with the two interpolations taken in the other order.
void warp_rows(const cv::Mat& image, const TabulatedKernel& kernel, bool simd, const GridField& field, cv::Rect region,
               cv::Range rows, cv::Mat& out) {
  const auto& g = field.grid;
  const RegionColumns columns = region_columns(region, g);
  const auto width = static_cast<std::size_t>(region.width);
  std::vector<double> xs(width), ys(width);
  std::vector<double> u_row(static_cast<std::size_t>(g.cols)), v_row(static_cast<std::size_t>(g.cols));
  // Only the node columns the region's pixels lie between (nodes_under):
  // a field may hold values there alone.
  const int first_column = columns.runs.empty() ? 0 : columns.runs.front().i0;
  const int last_column = columns.runs.empty() ? -1 : columns.runs.back().i1;
  const auto stride = static_cast<std::size_t>(image.step1());
  const auto sample = simd ? sample_separable : scalar_sample_separable;
  for (int y = rows.start; y < rows.end; ++y) {
    const double image_y = region.y + y;
    const AxisWeight wy = continued_axis_weight(image_y, g.y0_px, g.step_px, g.rows, kContinuedSteps);
    const auto lerp_rows = [&](const cv::Mat& values, std::vector<double>& row) {
      const double* r0 = values.ptr<double>(wy.i0);
      const double* r1 = values.ptr<double>(wy.i1);
      for (int c = first_column; c <= last_column; ++c) row[c] = r0[c] + wy.t * (r1[c] - r0[c]);
    };
    lerp_rows(field.u_px, u_row);
    lerp_rows(field.v_px, v_row);
    for (const ColumnRun& run : columns.runs) {
      const double u0 = u_row[run.i0], du = u_row[run.i1] - u0;
      const double v0 = v_row[run.i0], dv = v_row[run.i1] - v0;
      for (int x = run.begin; x < run.end; ++x) {
        xs[x] = columns.x_px[x] + (u0 + columns.t[x] * du);
        ys[x] = image_y + (v0 + columns.t[x] * dv);
      }
    }
    sample(image.ptr<float>(), stride, image.cols, image.rows, kernel, xs.data(), ys.data(), region.width,
           out.ptr<float>(y));
  }
}

// Rows `rows` of the region: the part inside the image copied whole, only
// the columns past its edges one by one.
void copy_with_replicated_border(const cv::Mat& image, cv::Rect region, cv::Range rows, cv::Mat& out) {
  const int inside_begin = std::clamp(-region.x, 0, region.width);
  const int inside_end = std::clamp(image.cols - region.x, inside_begin, region.width);
  for (int y = rows.start; y < rows.end; ++y) {
    const float* src = image.ptr<float>(std::clamp(region.y + y, 0, image.rows - 1));
    float* dst = out.ptr<float>(y);
    for (int x = 0; x < inside_begin; ++x) dst[x] = src[std::clamp(region.x + x, 0, image.cols - 1)];
    std::copy(src + region.x + inside_begin, src + region.x + inside_end, dst + inside_begin);
    for (int x = inside_end; x < region.width; ++x) dst[x] = src[std::clamp(region.x + x, 0, image.cols - 1)];
  }
}

}  // namespace

cv::Rect nodes_under(cv::Rect region, const GridGeometry& g) {
  const auto along_x = [&](int x) { return continued_axis_weight(x, g.x0_px, g.step_px, g.cols, kContinuedSteps); };
  const auto along_y = [&](int y) { return continued_axis_weight(y, g.y0_px, g.step_px, g.rows, kContinuedSteps); };
  const AxisWeight left = along_x(region.x), right = along_x(region.x + region.width - 1);
  const AxisWeight top = along_y(region.y), bottom = along_y(region.y + region.height - 1);
  return {left.i0, top.i0, right.i1 - left.i0 + 1, bottom.i1 - top.i0 + 1};
}

cv::Point2d interpolate_field(const GridField& field, double x_px, double y_px) {
  const auto& g = field.grid;
  const AxisWeight wx = axis_weight(x_px, g.x0_px, g.step_px, g.cols);
  const AxisWeight wy = axis_weight(y_px, g.y0_px, g.step_px, g.rows);
  return {bilinear(field.u_px, wx, wy), bilinear(field.v_px, wx, wy)};
}

GridSampler::GridSampler(const GridField& field, const std::vector<double>& x_px, const std::vector<double>& y_px)
    : field_(field) {
  const auto& g = field.grid;
  columns_.reserve(x_px.size());
  for (const double x : x_px) columns_.push_back(axis_weight(x, g.x0_px, g.step_px, g.cols));
  rows_.reserve(y_px.size());
  for (const double y : y_px) rows_.push_back(axis_weight(y, g.y0_px, g.step_px, g.rows));
}

namespace {

void warp(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator, bool simd,
          cv::Mat& out) {
  CV_Assert(image.type() == CV_32FC1);
  out.create(region.size(), CV_32F);
  CV_Assert(out.data != image.data);
  // Small regions (probes) cost less than waking the other thread.
  const auto for_region_rows = [&](auto rows_of) {
    if (region.area() < 16384) {
      rows_of(cv::Range(0, region.height));
    } else {
      cv::parallel_for_(cv::Range(0, region.height), rows_of);
    }
  };
  if (field.grid.rows == 0 || field.grid.cols == 0) {
    for_region_rows([&](const cv::Range& rows) { copy_with_replicated_border(image, region, rows, out); });
    return;
  }
  const TabulatedKernel kernel = table_of(interpolator).kernel();
  if (needs_coefficients(interpolator)) {
    // The coefficients' pixel (x, y) is the image's (x − border, y − border).
    constexpr int b = kCoefficientBorderPx;
    GridField shifted = field;
    shifted.grid.x0_px += b;
    shifted.grid.y0_px += b;
    const cv::Rect moved = region + cv::Point(b, b);
    for_region_rows([&](const cv::Range& rows) { warp_rows(image, kernel, simd, shifted, moved, rows, out); });
    return;
  }
  for_region_rows([&](const cv::Range& rows) { warp_rows(image, kernel, simd, field, region, rows, out); });
}

}  // namespace

cv::Mat warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator) {
  cv::Mat out;
  warp(image, field, region, interpolator, true, out);
  return out;
}

void warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator,
                 cv::Mat& out) {
  warp(image, field, region, interpolator, true, out);
}

bool needs_coefficients(Interpolator interpolator) {
  return interpolator == Interpolator::kBSpline3 || interpolator == Interpolator::kBSpline5;
}

void bspline_coefficients(const cv::Mat& image, Interpolator interpolator, cv::Mat& out) {
  CV_Assert(image.type() == CV_32FC1 && needs_coefficients(interpolator));
  constexpr int b = kCoefficientBorderPx;
  out.create(image.rows + 2 * b, image.cols + 2 * b, CV_32F);
  CV_Assert(out.data != image.data);
  cv::copyMakeBorder(image, out, b, b, b, b, cv::BORDER_REPLICATE);
  const std::vector<double> poles = prefilter_poles(interpolator);
  // Blocks of rows (gathered side by side), then blocks of columns; on all threads.
  constexpr int kRowBlock = 16, kColumnBlock = 64;
  cv::parallel_for_(cv::Range(0, (out.rows + kRowBlock - 1) / kRowBlock), [&](const cv::Range& blocks) {
    std::vector<double> lines;
    for (int b = blocks.start; b < blocks.end; ++b) {
      const int y0 = b * kRowBlock, count = std::min(kRowBlock, out.rows - y0);
      lines.resize(static_cast<std::size_t>(out.cols) * count);
      for (int j = 0; j < count; ++j) {
        const float* row = out.ptr<float>(y0 + j);
        for (int x = 0; x < out.cols; ++x) lines[std::size_t(x) * count + j] = row[x];
      }
      prefilter_lines(lines.data(), out.cols, count, poles);
      for (int j = 0; j < count; ++j) {
        float* row = out.ptr<float>(y0 + j);
        for (int x = 0; x < out.cols; ++x) row[x] = static_cast<float>(lines[std::size_t(x) * count + j]);
      }
    }
  });
  cv::parallel_for_(cv::Range(0, (out.cols + kColumnBlock - 1) / kColumnBlock), [&](const cv::Range& blocks) {
    std::vector<double> lines;
    for (int b = blocks.start; b < blocks.end; ++b) {
      const int x0 = b * kColumnBlock, count = std::min(kColumnBlock, out.cols - x0);
      lines.resize(static_cast<std::size_t>(out.rows) * count);
      for (int y = 0; y < out.rows; ++y) std::copy_n(out.ptr<float>(y) + x0, count, lines.begin() + std::ptrdiff_t(y) * count);
      prefilter_lines(lines.data(), out.rows, count, poles);
      for (int y = 0; y < out.rows; ++y) {
        float* row = out.ptr<float>(y) + x0;
        for (int j = 0; j < count; ++j) row[j] = static_cast<float>(lines[std::size_t(y) * count + j]);
      }
    }
  });
}

TabulatedKernel interpolation_kernel(Interpolator interpolator) { return table_of(interpolator).kernel(); }

cv::Mat scalar_warp_region(const cv::Mat& image, const GridField& field, cv::Rect region, Interpolator interpolator) {
  cv::Mat out;
  warp(image, field, region, interpolator, false, out);
  return out;
}

}  // namespace bosfuse::fusion
