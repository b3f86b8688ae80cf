#include "fusion/subpixel.h"

#include <algorithm>
#include <cmath>

namespace bosfuse::fusion {
namespace {

constexpr double kFloor = 1e-4;  // below any real ZNCC peak neighbour worth fitting

double safe_log(double c) { return std::log(std::max(c, kFloor)); }

double bounded(double offset) { return std::isfinite(offset) ? std::clamp(offset, -1.0, 1.0) : 0.0; }

}  // namespace

double gaussian_3point(double left, double centre, double right) {
  const double l = safe_log(left), c = safe_log(centre), r = safe_log(right);
  const double curvature = l - 2 * c + r;
  if (!(curvature < 0)) return 0.0;  // not a maximum: no better guess than the integer peak
  return bounded((l - r) / (2 * curvature));
}

double parabola_3point(double left, double centre, double right) {
  const double curvature = left - 2 * centre + right;
  if (!(curvature < 0)) return 0.0;
  return bounded((left - right) / (2 * curvature));
}

SubpixelOffset subpixel_offset(const std::array<double, 9>& c, SubpixelEstimator estimator) {
  if (estimator == SubpixelEstimator::kParabola3Point) {
    return {parabola_3point(c[3], c[4], c[5]), parabola_3point(c[1], c[4], c[7])};
  }
  const SubpixelOffset three_point{gaussian_3point(c[3], c[4], c[5]), gaussian_3point(c[1], c[4], c[7])};
  if (estimator == SubpixelEstimator::kGaussian3Point) return three_point;
  std::array<double, 9> L;
  for (int i = 0; i < 9; ++i) L[i] = safe_log(c[i]);
  // The nine-point basis {1, x, y, x²−2/3, xy, y²−2/3} is orthogonal, so each
  // least-squares coefficient is a projection.
  double a1 = 0, a2 = 0, a3 = 0, a4 = 0, a5 = 0;
  for (int j = -1; j <= 1; ++j) {
    for (int i = -1; i <= 1; ++i) {
      const double l = L[(j + 1) * 3 + (i + 1)];
      a1 += i * l / 6.0;
      a2 += j * l / 6.0;
      a3 += (i * i - 2.0 / 3.0) * l / 2.0;
      a4 += i * j * l / 4.0;
      a5 += (j * j - 2.0 / 3.0) * l / 2.0;
    }
  }
  const double det = 4 * a3 * a5 - a4 * a4;
  if (!(a3 < 0 && a5 < 0 && det > 0)) return three_point;
  const double dx = (a4 * a2 - 2 * a5 * a1) / det;
  const double dy = (a4 * a1 - 2 * a3 * a2) / det;
  if (!std::isfinite(dx) || !std::isfinite(dy) || std::abs(dx) > 1 || std::abs(dy) > 1) return three_point;
  return {dx, dy};
}

}  // namespace bosfuse::fusion
