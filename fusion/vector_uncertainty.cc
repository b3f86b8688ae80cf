#include "fusion/vector_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

// A window less its mean, row-major into `out`.
void centred(const cv::Mat& window, std::vector<double>& out) {
  const int n = window.rows;
  out.resize(static_cast<std::size_t>(n) * n);
  double sum = 0;
  for (int y = 0; y < n; ++y) {
    const float* row = window.ptr<float>(y);
    double* o = out.data() + static_cast<std::ptrdiff_t>(y) * n;
    for (int x = 0; x < n; ++x) {
      o[x] = row[x];
      sum += row[x];
    }
  }
  const double mean = sum / static_cast<double>(out.size());
  for (double& v : out) v -= mean;
}

// The variance of Σ d from its terms' spread, Σ (d − mean d)², as Wieneke
// takes it.
double variance_of_sum(const std::vector<double>& d) {
  double mean = 0;
  for (const double v : d) mean += v;
  mean /= static_cast<double>(d.size());
  double sum_sq = 0;
  for (const double v : d) sum_sq += (v - mean) * (v - mean);
  return sum_sq;
}

}  // namespace

double gaussian_peak_uncertainty(double c0, double c_pm, double sigma_delta) {
  const double high = c_pm + sigma_delta / 2, low = c_pm - sigma_delta / 2;
  if (!(low > 0) || !(c0 > 0) || !(c0 * c0 > high * low)) return kUnresolvedPx;
  const double sigma = std::log(high / low) / (2 * std::log(c0 * c0 / (high * low)));
  if (!std::isfinite(sigma)) return kUnresolvedPx;
  // Identical windows give σ_ΔC = 0; the floor keeps 0 meaning "not estimated".
  return std::clamp(std::abs(sigma), kFloorPx, kUnresolvedPx);
}

VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window,
                                         UncertaintyScratch& scratch) {
  const int n = reference_window.rows;
  if (n < 4 || reference_window.cols != n || measurement_window.size() != reference_window.size() ||
      reference_window.type() != CV_32FC1 || measurement_window.type() != CV_32FC1) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
  centred(reference_window, scratch.a);
  centred(measurement_window, scratch.b);
  const double* a = scratch.a.data();
  const double* b = scratch.b.data();
  scratch.dx.resize(static_cast<std::size_t>(n) * (n - 1));
  scratch.dy.resize(static_cast<std::size_t>(n - 1) * n);
  double c0 = 0, c_plus_x = 0, c_minus_x = 0, c_plus_y = 0, c_minus_y = 0;
  for (int y = 0; y < n; ++y) {
    const double* ar = a + static_cast<std::ptrdiff_t>(y) * n;
    const double* br = b + static_cast<std::ptrdiff_t>(y) * n;
    double* dxr = scratch.dx.data() + static_cast<std::ptrdiff_t>(y) * (n - 1);
    for (int x = 0; x < n; ++x) c0 += ar[x] * br[x];
    for (int x = 0; x + 1 < n; ++x) {
      const double plus = ar[x] * br[x + 1], minus = ar[x + 1] * br[x];
      c_plus_x += plus;
      c_minus_x += minus;
      dxr[x] = plus - minus;
    }
    if (y + 1 == n) break;
    const double* ar_below = ar + n;
    const double* br_below = br + n;
    double* dyr = scratch.dy.data() + static_cast<std::ptrdiff_t>(y) * n;
    for (int x = 0; x < n; ++x) {
      const double plus = ar[x] * br_below[x], minus = ar_below[x] * br[x];
      c_plus_y += plus;
      c_minus_y += minus;
      dyr[x] = plus - minus;
    }
  }
  const double sigma_dx = std::sqrt(variance_of_sum(scratch.dx));
  const double sigma_dy = std::sqrt(variance_of_sum(scratch.dy));
  // C± sum over n − 1 of the n columns (rows): C0 on as many pixels.
  const double c0_part = c0 * (n - 1) / n;
  return {gaussian_peak_uncertainty(c0_part, (c_plus_x + c_minus_x) / 2, sigma_dx),
          gaussian_peak_uncertainty(c0_part, (c_plus_y + c_minus_y) / 2, sigma_dy)};
}

}  // namespace bosfuse::fusion
