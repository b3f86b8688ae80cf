#include "fusion/vector_uncertainty.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {
namespace {

// Sums over the lines along one axis of the contributions d_i and their
// lag products, from which their variance is formed (variance_from).
constexpr int kMaxLags = 2;
struct LagSums {
  double sum = 0;                   // Σ d_i
  double products[kMaxLags + 1] = {};  // Σ d_i·d_(i+l), l = 0…lags
  double ends[kMaxLags + 1] = {};      // Σ over lines of the l first and l last d_i (l ≥ 1)
  int count = 0;                    // contributions
  int lines = 0;
  int length = 0;                   // contributions per line
};

// The variance of Σ d_i from the sums: Σ over lags −L…L of the products of
// the centred contributions, (d_i − m)(d_(i+l) − m) summed as
// Σ d_i·d_(i+l) − m·(2·Σ_line d − the l first and last) + m²·(length − l).
double variance_from(const LagSums& s, int lags) {
  const double m = s.count > 0 ? s.sum / s.count : 0;
  double total = s.products[0] - m * s.sum;
  for (int l = 1; l <= lags && l < s.length; ++l) {
    const double pairs = static_cast<double>(s.lines) * (s.length - l);
    total += 2 * (s.products[l] - m * (2 * s.sum - s.ends[l]) + m * m * pairs);
  }
  return std::max(total, 0.0);
}

// The first and last l contributions ΔCx of every row, l = 1 and 2, for
// variance_from's centring (the kernel sums the rows' ends along y).
void x_ends(const cv::Mat& a, const cv::Mat& b, double mean_a, double mean_b, double* ends) {
  const int n = a.rows;
  const float ma = static_cast<float>(mean_a), mb = static_cast<float>(mean_b);
  float one = 0, two = 0;
  for (int y = 0; y < n; ++y) {
    const float *ar = a.ptr<float>(y), *br = b.ptr<float>(y);
    const auto delta = [&](int x) { return (ar[x] - ma) * (br[x + 1] - mb) - (ar[x + 1] - ma) * (br[x] - mb); };
    const float outer = delta(0) + delta(n - 2);
    one += outer;
    two += outer + delta(1) + delta(n - 3);
  }
  ends[0] = one, ends[1] = two;
}

// The sums along one axis from the kernels' (simd_kernels.h).
LagSums axis_sums(int n, double sum, double squares, double lag1, double lag2, double ends1, double ends2) {
  LagSums s;
  s.lines = n, s.length = n - 1, s.count = n * (n - 1);
  s.sum = sum;
  s.products[0] = squares, s.products[1] = lag1, s.products[2] = lag2;
  s.ends[1] = ends1, s.ends[2] = ends2;
  return s;
}

void check_window(const cv::Mat& window) {
  if (window.rows < 4 || window.cols != window.rows || window.type() != CV_32FC1) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
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
                                          bool correlated_contributions) {
  const int n = reference_window.rows;
  check_window(reference_window);
  check_window(measurement_window);
  if (measurement_window.size() != reference_window.size()) {
    throw std::invalid_argument("correlation statistics need two equal square float windows of at least 4 px");
  }
  double sums[kCorrelationSumCount];
  correlation_statistics_sums(reference_window.ptr<float>(), reference_window.step1(), measurement_window.ptr<float>(),
                              measurement_window.step1(), n, sums);
  const int lags = correlated_contributions ? kContributionLags : 0;
  double lag[kCorrelationLagSumCount] = {}, ends[2] = {};
  if (lags > 0) {
    correlation_lag_sums(reference_window.ptr<float>(), reference_window.step1(), measurement_window.ptr<float>(),
                         measurement_window.step1(), n, lag);
    x_ends(reference_window, measurement_window, lag[kMeanA], lag[kMeanB], ends);
  }
  const double variance_x = variance_from(
      axis_sums(n, sums[kDeltaX], sums[kDeltaX2], lag[kLagX1], lag[kLagX2], ends[0], ends[1]), lags);
  const double variance_y = variance_from(
      axis_sums(n, sums[kDeltaY], sums[kDeltaY2], lag[kLagY1], lag[kLagY2], lag[kEndsY1], lag[kEndsY2]), lags);
  // C± sum over n − 1 of the n columns (rows): C0 on as many pixels.
  const double c0_part = sums[kC0] * (n - 1) / n;
  return {gaussian_peak_uncertainty(c0_part, (sums[kPlusX] + sums[kMinusX]) / 2, std::sqrt(variance_x)),
          gaussian_peak_uncertainty(c0_part, (sums[kPlusY] + sums[kMinusY]) / 2, std::sqrt(variance_y))};
}

double predictor_noise_gain(int window_px, int step_px, bool smoothed_predictor) {
  if (window_px < 1 || step_px < 1) throw std::invalid_argument("the predictor's noise gain needs a window and a step");
  // K along one axis: the window's mean of each node's bilinear hat, nodes
  // at −r…r steps (a window reaches at most window/(2·step) + 1 of them).
  const int r = window_px / (2 * step_px) + 1;
  std::vector<double> k(static_cast<std::size_t>(2 * r + 1), 0.0);
  for (int px = 0; px < window_px; ++px) {
    const double x = px - (window_px - 1) / 2.0;
    for (int j = -r; j <= r; ++j) {
      k[static_cast<std::size_t>(j + r)] += std::max(0.0, 1 - std::abs(x - j * step_px) / step_px) / window_px;
    }
  }
  const std::vector<double> smoothing = smoothed_predictor ? std::vector<double>{0.25, 0.5, 0.25} : std::vector<double>{1};
  // (δ − K)·S along one axis, then F = δ + that in two dimensions.
  const int m = static_cast<int>(smoothing.size()) / 2, width = 2 * (r + m) + 1;
  std::vector<double> ks(static_cast<std::size_t>(width), 0.0), s1(static_cast<std::size_t>(width), 0.0);
  for (int i = -r; i <= r; ++i) {
    for (int j = -m; j <= m; ++j) ks[static_cast<std::size_t>(i + j + r + m)] += k[i + r] * smoothing[j + m];
  }
  for (int j = -m; j <= m; ++j) s1[static_cast<std::size_t>(j + r + m)] = smoothing[j + m];
  double sum_sq = 0;
  for (int y = 0; y < width; ++y) {
    for (int x = 0; x < width; ++x) {
      const double f = (x == r + m && y == r + m ? 1.0 : 0.0) + s1[y] * s1[x] - ks[y] * ks[x];
      sum_sq += f * f;
    }
  }
  return std::sqrt(sum_sq);
}

VectorUncertainty with_predictor_noise(const VectorUncertainty& sigma, double gain) {
  const auto scaled = [&](double s) { return s >= kUnresolvedPx ? s : std::clamp(s * gain, kFloorPx, kUnresolvedPx); };
  return {scaled(sigma.sigma_u_px), scaled(sigma.sigma_v_px)};
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
