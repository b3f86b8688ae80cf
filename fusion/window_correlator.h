#pragma once
// WindowCorrelator computes the zero-normalised cross-correlation (ZNCC) of
// one interrogation window of the reference against every shift of it within
// ±radius px in a search patch of the measurement image:
//
//   c(s) = Σ a'(p)·b(p+s) / sqrt(Σ a'(p)² · Σ (b(p+s) − mean_s b)²),  a' = a − mean a
//
// so c ∈ [−1, 1] whatever the illumination of either window. Two ways give
// the same plane: direct summation, cheap when the search is small (BOS
// shifts are a few pixels), and FFT, cheap for large windows or searches;
// kAuto picks the cheaper by an operation count. Window sums use double;
// windows without variance give c = 0 rather than a division by zero.
//
// Two pairings of windows:
//  - kSearchArea: the reference window slides over the larger search patch
//    (the formula above). Robust for a first pass with shifts of several
//    pixels, but c(+1) and c(−1) pair different pixels, so even identical
//    windows give a slightly asymmetric peak (a few 0.01 px of bias);
//  - kEqualWindows: the measurement window of the same size at the same
//    place, correlated periodically (as FFT-based PIV does). The peak of two
//    identical windows is exactly symmetric, so after window deformation,
//    where the remaining shift is close to 0, it has no such bias. Used for
//    the refinement passes.
// One correlator per thread: it keeps scratch buffers between calls.
// A caller that correlates the same reference windows again and again (every
// pass of every frame) passes their WindowStats, computed once with
// window_stats(), instead of having them summed again for each call.

#include <opencv2/core.hpp>
#include <vector>

namespace bosfuse::fusion {

enum class CorrelationMethod { kAuto, kDirect, kFft };
enum class WindowPairing { kSearchArea, kEqualWindows };

struct CorrelationPlane {
  int radius = 0;             // shifts −radius..radius in x and y
  std::vector<double> value;  // (2·radius+1)² row-major, index (dy+radius)·side + (dx+radius)
  double reference_std = 0;   // sample standard deviation of the reference window

  int side() const { return 2 * radius + 1; }
  double at(int dx, int dy) const { return value[static_cast<std::size_t>((dy + radius) * side() + dx + radius)]; }
};

// Mean and energy Σ (a − mean)² of a window, summed in double.
struct WindowStats {
  double mean = 0;
  double energy = 0;
};

// The highest value of a plane (its first in row-major order) and how it
// stands out: the ratio to the highest value outside its 3×3 neighbourhood
// (floored at 0.01, so a plane near 0 elsewhere gives a finite ratio), and
// the ratio to the second peak, the highest local maximum outside it
// (Keane & Adrian's primary-to-secondary peak ratio, the same floor): the
// two differ where the peak is broader than its 3×3 (large dots), whose
// flank is no second peak; the no-peak tests take separate_ratio.
struct CorrelationPeak {
  int dx = 0;
  int dy = 0;
  double value = 0;
  double ratio = 0;
  double separate_ratio = 0;
};
CorrelationPeak find_peak(const CorrelationPlane& plane);

// `window` is n×n CV_32FC1 (a view into a larger image is fine).
WindowStats window_stats(const cv::Mat& window);

class WindowCorrelator {
 public:
  // `reference_window` is n×n, `search_patch` (n+2r)×(n+2r), both CV_32FC1
  // (views into larger images are fine). The patch's top-left is the window's
  // top-left shifted by (−r, −r).
  // With kEqualWindows the central n×n of the patch is the measurement
  // window, and the radius must be below n/2.
  // `reference_stats`, when given, must be window_stats(reference_window).
  void correlate(const cv::Mat& reference_window, const cv::Mat& search_patch, int radius_px, CorrelationMethod method,
                 CorrelationPlane& plane, WindowPairing pairing = WindowPairing::kSearchArea,
                 const WindowStats* reference_stats = nullptr);

  // Which method kAuto picks for an n-px window and a search radius.
  static CorrelationMethod cheaper_method(int window_px, int radius_px);

 private:
  void centre_reference(const cv::Mat& reference_window, double mean);
  // The equal-windows correlation in one SIMD kernel, where the target's
  // vectors fit the window (simd_kernels.h); false when they do not.
  bool correlate_in_registers(const cv::Mat& reference_window, double reference_mean, const cv::Mat& search_patch,
                              int radius_px, CorrelationPlane& plane);
  // √(Σa'² · the measurement window's energy); 0 where either window is flat.
  double denominator(double measurement_energy) const;
  // products_[shift] over a denominator; 0 over a flat pair's.
  double normalised(std::size_t shift, double denominator) const;
  void normalise_equal_windows(double measurement_energy, CorrelationPlane& plane) const;
  CorrelationMethod resolve(CorrelationMethod method, int window_px, int radius_px);
  void prepare_patch_sums(const cv::Mat& search_patch, int window_px);
  void direct_products(const cv::Mat& search_patch, int radius_px, int window_px);
  void fft_products(const cv::Mat& search_patch, int radius_px, int window_px);
  void normalise(int window_px, CorrelationPlane& plane) const;
  void correlate_equal_windows(const cv::Mat& search_patch, int radius_px, int window_px, CorrelationMethod method,
                               CorrelationPlane& plane);

  std::vector<float> centred_reference_;
  double reference_energy_ = 0;   // Σ a'²
  std::vector<double> products_;  // Σ a'·b per shift
  // Each shifted window's sum and sum of squares, (2r+1)² like the plane.
  std::vector<double> box_sum_, box_sum_sq_, column_scratch_;
  std::vector<float> periodic_;  // the centred measurement window tiled periodically, (n+2r)²
  // kAuto's choice for the last window size and radius: the operation count
  // costs more than a 16 px window's products.
  int auto_window_px_ = -1, auto_radius_px_ = -1;
  CorrelationMethod auto_method_ = CorrelationMethod::kDirect;
  cv::Mat fft_a_, fft_b_, spectrum_a_, spectrum_b_, product_spectrum_, correlation_;
};

}  // namespace bosfuse::fusion
