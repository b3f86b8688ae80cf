#include "fusion/vector_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

double mean_of(const cv::Mat& window) {
  double sum = 0;
  for (int y = 0; y < window.rows; ++y) {
    const float* row = window.ptr<float>(y);
    for (int x = 0; x < window.cols; ++x) sum += row[x];
  }
  return sum / (static_cast<double>(window.rows) * window.cols);
}

// The sums the estimator needs, each in four lanes that the compiler keeps
// in one vector register (a single double accumulator would serialise the
// loop on its additions): C0, C± along x and y, and Σ ΔC, Σ ΔC² along each.
struct Sums {
  static constexpr int kLanes = 4;
  enum Index { kC0, kPlusX, kMinusX, kPlusY, kMinusY, kDx, kDx2, kDy, kDy2, kCount };
  double lane[kCount][kLanes] = {};

  double total(Index i) const { return lane[i][0] + lane[i][1] + lane[i][2] + lane[i][3]; }
};

// One pixel's contributions at (x, y) into lane k: to C0, and with `kRight`
// and `kBelow` (known when compiled, so the lanes' loop has no branch) to
// C± and ΔC along x and y, `below` being the next row's pixels.
template <bool kRight, bool kBelow>
inline void add_pixel(Sums& s, int k, const float* a, const float* b, const float* a_below, const float* b_below,
                      int x, double mean_a, double mean_b) {
  const double a0 = a[x] - mean_a, b0 = b[x] - mean_b;
  s.lane[Sums::kC0][k] += a0 * b0;
  if constexpr (kRight) {
    const double a1 = a[x + 1] - mean_a, b1 = b[x + 1] - mean_b;
    const double plus = a0 * b1, minus = a1 * b0;
    s.lane[Sums::kPlusX][k] += plus;
    s.lane[Sums::kMinusX][k] += minus;
    s.lane[Sums::kDx][k] += plus - minus;
    s.lane[Sums::kDx2][k] += (plus - minus) * (plus - minus);
  }
  if constexpr (kBelow) {
    const double a1 = a_below[x] - mean_a, b1 = b_below[x] - mean_b;
    const double plus = a0 * b1, minus = a1 * b0;
    s.lane[Sums::kPlusY][k] += plus;
    s.lane[Sums::kMinusY][k] += minus;
    s.lane[Sums::kDy][k] += plus - minus;
    s.lane[Sums::kDy2][k] += (plus - minus) * (plus - minus);
  }
}

// A row's pixels: all but the last have a right neighbour.
template <bool kBelow>
void add_row(Sums& s, const float* a, const float* b, const float* a_below, const float* b_below, int n,
             double mean_a, double mean_b) {
  int x = 0;
  for (; x + Sums::kLanes < n; x += Sums::kLanes) {
    for (int k = 0; k < Sums::kLanes; ++k) add_pixel<true, kBelow>(s, k, a, b, a_below, b_below, x + k, mean_a, mean_b);
  }
  for (; x + 1 < n; ++x) add_pixel<true, kBelow>(s, 0, a, b, a_below, b_below, x, mean_a, mean_b);
  add_pixel<false, kBelow>(s, 0, a, b, a_below, b_below, n - 1, mean_a, mean_b);
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

VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window) {
  const int n = reference_window.rows;
  if (n < 4 || reference_window.cols != n || measurement_window.size() != reference_window.size() ||
      reference_window.type() != CV_32FC1 || measurement_window.type() != CV_32FC1) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
  const double mean_a = mean_of(reference_window), mean_b = mean_of(measurement_window);
  Sums s;
  for (int y = 0; y + 1 < n; ++y) {
    add_row<true>(s, reference_window.ptr<float>(y), measurement_window.ptr<float>(y),
                  reference_window.ptr<float>(y + 1), measurement_window.ptr<float>(y + 1), n, mean_a, mean_b);
  }
  add_row<false>(s, reference_window.ptr<float>(n - 1), measurement_window.ptr<float>(n - 1), nullptr, nullptr, n,
                 mean_a, mean_b);
  // ΔC has n(n − 1) terms along each axis; its variance as their spread.
  const double terms = static_cast<double>(n) * (n - 1);
  const auto spread = [&](Sums::Index sum, Sums::Index sum_sq) {
    const double total = s.total(sum);
    return std::sqrt(std::max(s.total(sum_sq) - total * total / terms, 0.0));
  };
  // C± sum over n − 1 of the n columns (rows): C0 on as many pixels.
  const double c0_part = s.total(Sums::kC0) * (n - 1) / n;
  return {gaussian_peak_uncertainty(c0_part, (s.total(Sums::kPlusX) + s.total(Sums::kMinusX)) / 2,
                                    spread(Sums::kDx, Sums::kDx2)),
          gaussian_peak_uncertainty(c0_part, (s.total(Sums::kPlusY) + s.total(Sums::kMinusY)) / 2,
                                    spread(Sums::kDy, Sums::kDy2))};
}

}  // namespace bosfuse::fusion
