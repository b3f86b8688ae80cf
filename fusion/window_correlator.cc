#include "fusion/window_correlator.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "fusion/simd_kernels.h"

namespace bosfuse::fusion {
namespace {

// Below this (in squared full-scale units summed over a window) a window is
// flat to float precision: its correlation is meaningless.
constexpr double kMinEnergy = 1e-12;

// max(floor, the highest of values[0, count)), NaNs passed over, in four
// independent chains: the maximum of a noisy plane changes at unpredictable
// shifts, where a branch per value mispredicts.
double highest(const double* values, int count, double floor) {
  double m[4] = {floor, floor, floor, floor};
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    for (int k = 0; k < 4; ++k) m[k] = std::max(m[k], values[i + k]);
  }
  for (; i < count; ++i) m[0] = std::max(m[0], values[i]);
  return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
}

// The highest local maximum of the plane (a value no in-plane neighbour
// exceeds) outside the 3×3 around (px, py), below the floor when there is
// none; `ceiling` is the highest value there, where the scan may stop. A
// broad peak's flank is no local maximum: with 6 px dots the highest value
// outside the 3×3 lies on it at 0.6 of the peak, and a true peak read as
// noise (docs/BENCHMARKS.md, "Background: dot size and coverage").
double highest_separate_peak(const CorrelationPlane& plane, int px, int py, double ceiling) {
  constexpr double kNone = -2.0;
  const int side = plane.side();
  const double* value = plane.value.data();
  double best = kNone;
  for (int y = 0; y < side && best < ceiling; ++y) {
    for (int x = 0; x < side; ++x) {
      const double v = value[static_cast<std::ptrdiff_t>(y) * side + x];
      if (!(v > best) || (std::abs(x - px) <= 1 && std::abs(y - py) <= 1)) continue;
      bool local_maximum = true;
      for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, side - 1) && local_maximum; ++ny) {
        for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, side - 1); ++nx) {
          if (value[static_cast<std::ptrdiff_t>(ny) * side + nx] > v) {
            local_maximum = false;
            break;
          }
        }
      }
      if (local_maximum) best = v;
    }
  }
  return best;
}

}  // namespace

// The highest value (its first in row-major order, as a scan taking only a
// higher value finds it), and the highest outside its 3×3 neighbourhood.
CorrelationPeak find_peak(const CorrelationPlane& plane) {
  constexpr double kBelowAny = -2.0;  // correlations lie in [−1, 1]
  const int r = plane.radius, side = plane.side();
  const double* value = plane.value.data();
  CorrelationPeak peak{0, 0, highest(value, side * side, kBelowAny), 0};
  if (peak.value > kBelowAny) {
    const int at = static_cast<int>(std::find(value, value + side * side, peak.value) - value);
    peak.dx = at % side - r;
    peak.dy = at / side - r;
  }
  const int px = peak.dx + r, py = peak.dy + r;
  double second = kBelowAny;
  for (int y = 0; y < side; ++y) {
    const double* row = value + static_cast<std::ptrdiff_t>(y) * side;
    if (std::abs(y - py) > 1) {
      second = highest(row, side, second);
    } else {
      const int left_end = std::max(px - 1, 0), right_begin = std::min(px + 2, side);
      second = highest(row, left_end, second);
      second = highest(row + right_begin, side - right_begin, second);
    }
  }
  // A floor keeps the ratio finite when the rest of the plane is near 0 or
  // negative; ratios above 100 mean "unambiguous" anyway.
  peak.ratio = peak.value / std::max(second, 0.01);
  peak.separate_ratio = peak.value / std::max(highest_separate_peak(plane, px, py, second), 0.01);
  return peak;
}

CorrelationMethod WindowCorrelator::cheaper_method(int window_px, int radius_px) {
  const double shifts = std::pow(2.0 * radius_px + 1, 2);
  const double direct = shifts * window_px * window_px;
  const int n = cv::getOptimalDFTSize(window_px + 2 * radius_px);
  // Three real 2-D transforms, ~2.5·N²·log2(N²) each, plus the spectrum product.
  const double fft = 3 * 2.5 * n * n * std::log2(double(n) * n) + 4.0 * n * n;
  return direct <= fft ? CorrelationMethod::kDirect : CorrelationMethod::kFft;
}

WindowStats window_stats(const cv::Mat& window) {
  CV_Assert(window.type() == CV_32FC1 && window.rows == window.cols);
  WindowStats stats;
  window_mean_energy(window.ptr<float>(), window.step1(), window.rows, &stats.mean, &stats.energy);
  return stats;
}

CorrelationMethod WindowCorrelator::resolve(CorrelationMethod method, int window_px, int radius_px) {
  if (method != CorrelationMethod::kAuto) return method;
  if (window_px != auto_window_px_ || radius_px != auto_radius_px_) {
    auto_method_ = cheaper_method(window_px, radius_px);
    auto_window_px_ = window_px;
    auto_radius_px_ = radius_px;
  }
  return auto_method_;
}

void WindowCorrelator::correlate(const cv::Mat& reference_window, const cv::Mat& search_patch, int radius_px,
                                 CorrelationMethod method, CorrelationPlane& plane, WindowPairing pairing,
                                 const WindowStats* reference_stats) {
  CV_Assert(reference_window.type() == CV_32FC1 && search_patch.type() == CV_32FC1);
  const int n = reference_window.rows;
  CV_Assert(reference_window.cols == n && search_patch.rows == n + 2 * radius_px &&
            search_patch.cols == n + 2 * radius_px);
  plane.radius = radius_px;
  plane.value.assign(static_cast<std::size_t>(plane.side() * plane.side()), 0.0);
  const WindowStats stats = reference_stats ? *reference_stats : window_stats(reference_window);
  reference_energy_ = stats.energy;
  plane.reference_std = n > 1 ? std::sqrt(reference_energy_ / (double(n) * n - 1)) : 0.0;
  method = resolve(method, n, radius_px);
  if (pairing == WindowPairing::kEqualWindows && method == CorrelationMethod::kDirect &&
      correlate_in_registers(reference_window, stats.mean, search_patch, radius_px, plane)) {
    return;
  }
  centre_reference(reference_window, stats.mean);
  if (pairing == WindowPairing::kEqualWindows) {
    correlate_equal_windows(search_patch, radius_px, n, method, plane);
    return;
  }
  prepare_patch_sums(search_patch, n);
  if (method == CorrelationMethod::kDirect) {
    direct_products(search_patch, radius_px, n);
  } else {
    fft_products(search_patch, radius_px, n);
  }
  normalise(n, plane);
}

void WindowCorrelator::centre_reference(const cv::Mat& reference_window, double mean) {
  const int n = reference_window.rows;
  centred_reference_.resize(static_cast<std::size_t>(n) * n);
  centre_window(reference_window.ptr<float>(), reference_window.step1(), n, mean, centred_reference_.data());
}

bool WindowCorrelator::correlate_in_registers(const cv::Mat& reference_window, double reference_mean,
                                              const cv::Mat& search_patch, int radius_px, CorrelationPlane& plane) {
  const int n = reference_window.rows;
  const int side = 2 * radius_px + 1;
  products_.resize(static_cast<std::size_t>(side) * side);
  double mean = 0, energy = 0;
  const float* window = search_patch.ptr<float>(radius_px) + radius_px;
  if (!equal_window_products(reference_window.ptr<float>(), reference_window.step1(), reference_mean, window,
                             search_patch.step1(), n, radius_px, products_.data(), &mean, &energy)) {
    return false;
  }
  normalise_equal_windows(energy, plane);
  return true;
}

void WindowCorrelator::prepare_patch_sums(const cv::Mat& search_patch, int window_px) {
  const int p = search_patch.rows;
  const auto side = static_cast<std::size_t>(p - window_px + 1);
  column_scratch_.resize(2 * static_cast<std::size_t>(side) * p);
  box_sum_.resize(side * side);
  box_sum_sq_.resize(side * side);
  patch_box_sums(search_patch.ptr<float>(), search_patch.step1(), p, window_px, column_scratch_.data(), box_sum_.data(),
                 box_sum_sq_.data());
}

void WindowCorrelator::direct_products(const cv::Mat& search_patch, int radius_px, int n) {
  const int side = 2 * radius_px + 1;
  products_.assign(static_cast<std::size_t>(side) * side, 0.0);
  accumulate_products(centred_reference_.data(), search_patch.ptr<float>(0), search_patch.step1(), n, side,
                      products_.data());
}

void WindowCorrelator::fft_products(const cv::Mat& search_patch, int radius_px, int n) {
  const int p = search_patch.rows;
  const int size = cv::getOptimalDFTSize(p);
  fft_a_.create(size, size, CV_32F);
  fft_b_.create(size, size, CV_32F);
  fft_a_.setTo(0);
  fft_b_.setTo(0);
  cv::Mat(n, n, CV_32F, centred_reference_.data()).copyTo(fft_a_(cv::Rect(0, 0, n, n)));
  search_patch.copyTo(fft_b_(cv::Rect(0, 0, p, p)));
  cv::dft(fft_a_, spectrum_a_, 0, n);
  cv::dft(fft_b_, spectrum_b_, 0, p);
  // B·conj(A) is the spectrum of Σ a(p) b(p+s); the patch is padded to at
  // least n+2r so shifts 0..2r never wrap around.
  cv::mulSpectrums(spectrum_b_, spectrum_a_, product_spectrum_, 0, true);
  cv::dft(product_spectrum_, correlation_, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  const int side = 2 * radius_px + 1;
  products_.assign(static_cast<std::size_t>(side) * side, 0.0);
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx)
      products_[static_cast<std::size_t>(dy) * side + dx] = correlation_.at<float>(dy, dx);
  }
}

void WindowCorrelator::correlate_equal_windows(const cv::Mat& search_patch, int radius_px, int n,
                                               CorrelationMethod method, CorrelationPlane& plane) {
  CV_Assert(2 * radius_px < n);
  const float* window = search_patch.ptr<float>(radius_px) + radius_px;
  const std::size_t stride = search_patch.step1();
  double mean = 0, energy = 0;
  window_mean_energy(window, stride, n, &mean, &energy);
  const int p = n + 2 * radius_px;
  periodic_.resize(static_cast<std::size_t>(p) * p);
  centred_periodic_tile(window, stride, n, radius_px, static_cast<float>(mean), periodic_.data());
  const int side = 2 * radius_px + 1;
  products_.resize(static_cast<std::size_t>(side) * side);
  if (method == CorrelationMethod::kDirect) {
    accumulate_products(centred_reference_.data(), periodic_.data(), static_cast<std::size_t>(p), n, side,
                        products_.data());
  } else {
    // Transforms of exactly n×n are periodic over the window.
    cv::Mat a(n, n, CV_32F, centred_reference_.data());
    cv::Mat b = cv::Mat(p, p, CV_32F, periodic_.data())(cv::Rect(radius_px, radius_px, n, n)).clone();
    cv::dft(a, spectrum_a_);
    cv::dft(b, spectrum_b_);
    cv::mulSpectrums(spectrum_b_, spectrum_a_, product_spectrum_, 0, true);
    cv::dft(product_spectrum_, correlation_, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
    for (int dy = -radius_px; dy <= radius_px; ++dy) {
      for (int dx = -radius_px; dx <= radius_px; ++dx) {
        products_[static_cast<std::size_t>(dy + radius_px) * side + dx + radius_px] =
            correlation_.at<float>((dy + n) % n, (dx + n) % n);
      }
    }
  }
  normalise_equal_windows(energy, plane);
}

double WindowCorrelator::denominator(double measurement_energy) const {
  const bool flat = reference_energy_ < kMinEnergy || measurement_energy < kMinEnergy;
  return flat ? 0.0 : std::sqrt(reference_energy_ * measurement_energy);
}

double WindowCorrelator::normalised(std::size_t shift, double denominator) const {
  return denominator == 0.0 ? 0.0 : products_[shift] / denominator;
}

void WindowCorrelator::normalise_equal_windows(double measurement_energy, CorrelationPlane& plane) const {
  // One denominator for every shift, taken once: errno keeps the compiler
  // from hoisting a square root out of the loop itself.
  const double d = denominator(measurement_energy);
  for (std::size_t i = 0; i < plane.value.size(); ++i) plane.value[i] = normalised(i, d);
}

void WindowCorrelator::normalise(int n, CorrelationPlane& plane) const {
  normalise_by_energies(products_.data(), box_sum_.data(), box_sum_sq_.data(), plane.value.size(), double(n) * n,
                        reference_energy_, kMinEnergy, plane.value.data());
}

}  // namespace bosfuse::fusion
