#include "fusion/vector_uncertainty.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <stdexcept>

#include "fusion/simd_kernels.h"

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

// The factors by which the per-pixel sum Σ ΔC_i² over-states the variance
// of Σ ΔC_i along x and y, from the reference window's texture a.
// Noise in pixel k of b enters two neighbouring contributions, ΔC_(k−1)
// with a'(k−1) and ΔC_k with −a'(k+1) (noise in a likewise, signs swapped):
// per unit noise variance Σ ΔC has variance Σ_k (a(k−1) − a(k+1))², while
// the per-pixel sum counts Σ_i a'(i)² + a'(i+1)² = 2·Σ a'² less the first
// and last column's (row's). Their ratio is 1 − ρ(2 px) of the pattern's
// autocorrelation; 1 for white texture.
NeighbourNoiseFactors noise_factors_about(const cv::Mat& a, double mean_a) {
  // Sums of squares only, no differences of large sums: float lanes (eight,
  // which the compiler vectorises) hold them to 1e-6, each row's total then
  // added in double.
  constexpr int kLanes = 8;
  const int n = a.rows;
  const float mean = static_cast<float>(mean_a);
  double energy = 0, shared_x = 0, shared_y = 0, edge_columns = 0, edge_rows = 0;
  const auto total = [](const float* lanes) {
    double sum = 0;
    for (int k = 0; k < kLanes; ++k) sum += lanes[k];
    return sum;
  };
  for (int y = 0; y < n; ++y) {
    const float* row = a.ptr<float>(y);
    float e[kLanes] = {}, sx[kLanes] = {}, sy[kLanes] = {};
    int x = 0;
    for (; x + kLanes + 2 <= n; x += kLanes) {
      for (int k = 0; k < kLanes; ++k) {
        const float centred = row[x + k] - mean, across = row[x + k] - row[x + k + 2];
        e[k] += centred * centred;
        sx[k] += across * across;
      }
    }
    for (; x < n; ++x) {
      e[0] += (row[x] - mean) * (row[x] - mean);
      if (x + 2 < n) sx[0] += (row[x] - row[x + 2]) * (row[x] - row[x + 2]);
    }
    if (y + 2 < n) {
      const float* two_below = a.ptr<float>(y + 2);
      for (x = 0; x + kLanes <= n; x += kLanes) {
        for (int k = 0; k < kLanes; ++k) sy[k] += (row[x + k] - two_below[x + k]) * (row[x + k] - two_below[x + k]);
      }
      for (; x < n; ++x) sy[0] += (row[x] - two_below[x]) * (row[x] - two_below[x]);
    }
    const double row_energy = total(e);
    energy += row_energy;
    shared_x += total(sx);
    shared_y += total(sy);
    edge_columns += (row[0] - mean_a) * (row[0] - mean_a) + (row[n - 1] - mean_a) * (row[n - 1] - mean_a);
    if (y == 0 || y == n - 1) edge_rows += row_energy;
  }
  const auto ratio = [](double shared, double counted) {
    return counted > 0 ? std::clamp(shared / counted, 0.0, 2.0) : 1.0;
  };
  return {ratio(shared_x, 2 * energy - edge_columns), ratio(shared_y, 2 * energy - edge_rows)};
}

void check_window(const cv::Mat& window) {
  if (window.rows < 4 || window.cols != window.rows || window.type() != CV_32FC1) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
}

}  // namespace

NeighbourNoiseFactors neighbour_noise_factors(const cv::Mat& reference_window) {
  check_window(reference_window);
  return noise_factors_about(reference_window, mean_of(reference_window));
}

double gaussian_peak_uncertainty(double c0, double c_pm, double sigma_delta) {
  const double high = c_pm + sigma_delta / 2, low = c_pm - sigma_delta / 2;
  if (!(low > 0) || !(c0 > 0) || !(c0 * c0 > high * low)) return kUnresolvedPx;
  const double sigma = std::log(high / low) / (2 * std::log(c0 * c0 / (high * low)));
  if (!std::isfinite(sigma)) return kUnresolvedPx;
  // Identical windows give σ_ΔC = 0; the floor keeps 0 meaning "not estimated".
  return std::clamp(std::abs(sigma), kFloorPx, kUnresolvedPx);
}

VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window,
                                          bool independent_noise) {
  check_window(reference_window);
  return correlation_statistics(reference_window, measurement_window,
                                independent_noise ? neighbour_noise_factors(reference_window) : NeighbourNoiseFactors{});
}

VectorUncertainty correlation_statistics(const cv::Mat& reference_window, const cv::Mat& measurement_window,
                                          const NeighbourNoiseFactors& shared) {
  const int n = reference_window.rows;
  check_window(reference_window);
  check_window(measurement_window);
  if (measurement_window.size() != reference_window.size()) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
  double sums[kCorrelationSumCount];
  correlation_statistics_sums(reference_window.ptr<float>(), reference_window.step1(), measurement_window.ptr<float>(),
                              measurement_window.step1(), n, sums);
  // ΔC has n(n − 1) terms along each axis; its variance as their spread.
  const double terms = static_cast<double>(n) * (n - 1);
  const auto spread = [&](CorrelationSum sum, CorrelationSum sum_sq, double factor) {
    return std::sqrt(std::max(sums[sum_sq] - sums[sum] * sums[sum] / terms, 0.0) * factor);
  };
  // C± sum over n − 1 of the n columns (rows): C0 on as many pixels.
  const double c0_part = sums[kC0] * (n - 1) / n;
  return {gaussian_peak_uncertainty(c0_part, (sums[kPlusX] + sums[kMinusX]) / 2,
                                    spread(kDeltaX, kDeltaX2, shared.along_x)),
          gaussian_peak_uncertainty(c0_part, (sums[kPlusY] + sums[kMinusY]) / 2,
                                    spread(kDeltaY, kDeltaY2, shared.along_y))};
}

void add_held_deformation_uncertainty(const GridField& predictor, DisplacementField& field, const cv::Mat* only) {
  if (field.rows != predictor.u_px.rows || field.cols != predictor.u_px.cols) {
    throw std::invalid_argument("the deformation's grid is not the field's");
  }
  for (int row = 0; row < field.rows; ++row) {
    const bool outer_row = row == 0 || row == field.rows - 1;
    for (int col = 0; col < field.cols; ++col) {
      if (!outer_row && col != 0 && col != field.cols - 1) continue;
      if (only && !only->at<std::uint8_t>(row, col)) continue;
      DisplacementVector& vec = field.at(row, col);
      if (!vec.valid() || vec.sigma_u_px <= 0) continue;  // only measured vectors with a σ
      vec.sigma_u_px = std::hypot(vec.sigma_u_px, vec.u_px - predictor.u_px.at<double>(row, col));
      vec.sigma_v_px = std::hypot(vec.sigma_v_px, vec.v_px - predictor.v_px.at<double>(row, col));
    }
  }
}

}  // namespace bosfuse::fusion
