#pragma once
// SIMD kernels: the inner loops of displacement evaluation, written once with
// Google Highway and compiled for every x86 target it knows (SSSE3, SSE4,
// AVX2, AVX-512) plus a portable C++ one; the first call picks the best
// target this CPU runs (runtime dispatch), so one binary uses AVX-512 on a
// workstation and SSE4 on an old logger PC. Use these rather than writing a
// vectorised loop inline; each kernel has a scalar reference beside it that
// states its contract and that the tests hold it to.
//
// Choosing the target: limit_simd_targets caps what the dispatch may pick
// (the program sets it from the environment variable BOSFUSE_SIMD at its
// start, pipeline/simd_environment.h, whose values parse_simd_limit reads):
//   "" or "auto"    the best target the CPU has (also without a cap);
//   "avx2", "sse4"  at most that target (lower if the CPU lacks it);
//   "portable"      Highway's portable C++ target, no intrinsics
//                   ("SCALAR" with GCC < 12.3, else "EMU128").
// It is for comparing targets on one machine and for ruling out a SIMD path
// when results look wrong; results of all targets agree to float rounding.
// The cap is process-wide (Highway keeps one chosen target per process).

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace bosfuse::fusion {

// products[dy·side + dx] = Σ_{y,x < n} reference[y·n + x] · patch[(y + dy)·patch_stride + x + dx]
// for every shift dx, dy in [0, side): the numerator of a direct
// correlation. `reference` is n×n, contiguous; the patch is at least
// (n + side − 1)² with rows `patch_stride` floats apart. Each column of the
// window is accumulated in float over the n rows (exact enough for n ≤ 128
// values of order 1), the n column sums then added in double, in column
// order (the SIMD kernel adds them in double in a tree order instead). Any
// n ≥ 1 and side ≥ 1.
void accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                         double* products);

// The reference for accumulate_products: plain loops, the same sums in the
// same order. The SIMD kernel differs from it only by float rounding (targets
// with FMA round a product and its sum once, not twice).
void scalar_accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                                double* products);

// The mean and the energy Σ (x − mean)² of an n×n window (rows `stride`
// floats apart), both summed in double: a window's energy may be a small
// difference of large sums, which float would lose (1e-3 for a window at the
// texture limit against 256 for Σ x² of a bright one). Two passes, as the
// scalar reference does; the SIMD kernel sums in lanes of doubles, so the
// two differ by double rounding only. Any n ≥ 1.
void window_mean_energy(const float* window, std::size_t stride, int n, double* mean, double* energy);

// The reference for window_mean_energy: plain loops in row order.
void scalar_window_mean_energy(const float* window, std::size_t stride, int n, double* mean, double* energy);

// out[y·n + x] = window(y, x) − mean, the difference taken in double and
// rounded to float once: a reference window centred as precisely as float
// holds it. Exact operations, so the SIMD kernel and the reference agree
// exactly. Any n ≥ 1.
void centre_window(const float* window, std::size_t stride, int n, double mean, float* out);

// The reference for centre_window: plain loops.
void scalar_centre_window(const float* window, std::size_t stride, int n, double mean, float* out);

// The n×n window (rows `stride` floats apart) less `mean`, tiled
// periodically over (n + 2·radius)² floats written row-major to `out`:
// out[y·(n + 2r) + x] = window((y − r) mod n, (x − r) mod n) − mean. With
// radius 0 it is the centred window itself. One float subtraction per
// value, so the SIMD kernel and the reference agree exactly.
// 0 ≤ radius < n.
void centred_periodic_tile(const float* window, std::size_t stride, int n, int radius, float mean, float* out);

// The reference for centred_periodic_tile: plain loops with a modulo.
void scalar_centred_periodic_tile(const float* window, std::size_t stride, int n, int radius, float mean, float* out);

// For every n×n box of a p×p patch (rows `stride` floats apart), at offset
// (dx, dy) in [0, side)² with side = p − n + 1: the sum of its values and of
// their squares, in double, at sums[dy·side + dx] and squares[dy·side + dx].
// They normalise a search-area correlation (each shifted window's energy is
// squares − sums²/n²). The kernel slides: column sums over n rows moved down
// a row at a time, boxes moved right a column at a time, all in double,
// which differs from summing each box afresh by double rounding only. Every
// target does the same operations in the same order, so all give the same
// sums (a float's square is exact in double, so whether the compiler fuses
// square and sum into one multiply-add does not matter either).
// `column_scratch` holds 2·(p − n + 1)·p doubles.
void patch_box_sums(const float* patch, std::size_t stride, int p, int n, double* column_scratch, double* sums,
                    double* squares);

// The reference for patch_box_sums: each box summed afresh, in row order.
void scalar_patch_box_sums(const float* patch, std::size_t stride, int p, int n, double* sums, double* squares);

// The search-area correlation's normalisation, for `count` shifts:
// out[i] = products[i] / √(reference_energy · energy_i), where a shifted
// window's energy is energy_i = squares[i] − sums[i]²/window_pixels
// (patch_box_sums' boxes), and 0 where either energy is below min_energy (a
// flat window: no texture to correlate) or the root is 0. The SIMD kernel
// does the scalar reference's IEEE operations in its order, so the two are
// equal exactly.
void normalise_by_energies(const double* products, const double* sums, const double* squares, std::size_t count,
                           double window_pixels, double reference_energy, double min_energy, double* out);

// The reference for normalise_by_energies: one shift at a time.
void scalar_normalise_by_energies(const double* products, const double* sums, const double* squares, std::size_t count,
                                  double window_pixels, double reference_energy, double min_energy, double* out);

// The equal-windows correlation (window_correlator.h) of an n×n reference
// window and an n×n measurement window in one call: the measurement's mean
// and energy, as window_mean_energy gives them, and
//   products[dy·side + dx] = Σ_{y,x < n} (ref(y, x) − reference_mean) ·
//                            (win((y + dy − r) mod n, (x + dx − r) mod n) − mean)
// for side = 2r + 1, i.e. accumulate_products of the centred reference over
// centred_periodic_tile's tile. The SIMD kernel does it only where a window
// row is exactly one vector of the target (n = 16 with AVX-512, 8 with
// AVX2) and r is 1 or 2, the refinement passes' usual case; it then keeps
// the tile in registers and sums in float within a lane, so it agrees with
// the reference to float rounding. Elsewhere it returns false and writes
// nothing: the caller takes the general kernels.
bool equal_window_products(const float* reference, std::size_t reference_stride, double reference_mean,
                           const float* window, std::size_t stride, int n, int radius, double* products, double* mean,
                           double* energy);

// The reference for equal_window_products, for any n and 0 ≤ r < n/2:
// the scalar references of the kernels it replaces, one after the other.
void scalar_equal_window_products(const float* reference, std::size_t reference_stride, double reference_mean,
                                  const float* window, std::size_t stride, int n, int radius, double* products,
                                  double* mean, double* energy);

// Medians of many sets of eight values at once, for the median tests of a
// field's nodes against their eight neighbours (outlier_filter.h,
// adaptive_refinement.h). Set j's values are values[k·stride + j], k < 8,
// j < count (by position, so one vector load takes a position of several
// sets). medians[j] = (a₃ + a₄)/2 of the sorted values a₀ ≤ … ≤ a₇. Exact
// operations (min, max, one sum and a halving), so the SIMD kernel and the
// reference agree exactly. Values must be finite.
void medians_of_eight(const double* values, std::size_t stride, std::size_t count, double* medians);

// The reference for medians_of_eight: each set sorted on its own.
void scalar_medians_of_eight(const double* values, std::size_t stride, std::size_t count, double* medians);

// The normalised median test's residual for each set of medians_of_eight's
// layout and its centre value: with m the set's median and d the median of
// |a_k − m|, residuals[j] = |centres[j] − m| / (d + epsilon). The same
// exact operations and one division in both kernels: equal exactly.
void normalised_residuals_of_eight(const double* values, std::size_t stride, std::size_t count, const double* centres,
                                   double epsilon, double* residuals);

// The reference for normalised_residuals_of_eight.
void scalar_normalised_residuals_of_eight(const double* values, std::size_t stride, std::size_t count,
                                          const double* centres, double epsilon, double* residuals);

// out[j] = Σ_{k < taps} weights[k] · inputs[k][j] for j < count, summed in
// k order: one direction of a separable filter in double, along a row
// (inputs[k] = the row advanced by k elements) or across rows (inputs[k] =
// row k). The SIMD kernel differs from the reference by double rounding only
// (targets with FMA round each product and its sum once). Any taps ≥ 1.
void weighted_sum(const double* const* inputs, int taps, const double* weights, std::size_t count, double* out);

// The reference for weighted_sum: plain loops.
void scalar_weighted_sum(const double* const* inputs, int taps, const double* weights, std::size_t count, double* out);

// A separable interpolation kernel tabulated over the sub-pixel position
// t ∈ [0, 1]: entry e (0 ≤ e ≤ steps) holds its `taps` weights at
// t = e / steps, the first for the tap at floor(x) + 1 − taps/2 (taps even,
// 2..8); between entries the weights are interpolated linearly.
// `weights` holds (steps + 1)·taps floats and then at least 8 more (any
// value), which vector loads may read.
struct TabulatedKernel {
  const float* weights = nullptr;
  int taps = 0;
  int steps = 0;
};

// The kernel's weights at t ∈ [0, 1]: w[k] = a[k] + f·(b[k] − a[k]) for the
// entries a, b around t·steps. `weights` has room for kernel.taps floats.
void tabulated_weights(const TabulatedKernel& kernel, double t, float* weights);

// out[k] = Σ_j wy_j · Σ_i wx_i · image(floor(y[k]) + 1 − taps/2 + j, floor(x[k]) + 1 − taps/2 + i)
// for k < count, wx and wy the kernel's weights at the sub-pixel parts of
// x[k] and y[k]: the window deformation's resampling at `count` points of
// the image (x right, y down, in pixels). Taps outside the image are clamped
// to its edge (replicated border), so a point may lie anywhere. `image` is
// rows×cols floats with rows `stride` floats apart. Where eight neighbouring
// points' taps start at consecutive columns of one row (a smooth field's
// do) and the CPU has 8-lane vectors, the SIMD kernel samples them one per
// lane, summing as the reference does (each row of taps, then the rows);
// other points one by one, each tap column over the rows first, then the
// columns. Either way the two differ only by float rounding.
void sample_separable(const float* image, std::size_t stride, int cols, int rows, const TabulatedKernel& kernel,
                      const double* x, const double* y, int count, float* out);

// The reference for sample_separable: plain loops, the weights from
// tabulated_weights, each row of taps summed in float, then the rows
// weighted and added in row order.
void scalar_sample_separable(const float* image, std::size_t stride, int cols, int rows, const TabulatedKernel& kernel,
                             const double* x, const double* y, int count, float* out);

// The sums the per-vector uncertainty's correlation statistics
// (vector_uncertainty.h) need of two n×n windows a and b (rows `a_stride`,
// `b_stride` floats apart), each less its own mean a', b':
//   sums[kC0]     = Σ a'(y, x)·b'(y, x) over every pixel,
//   sums[kPlusX]  = Σ a'(y, x)·b'(y, x + 1), sums[kMinusX] = Σ a'(y, x + 1)·b'(y, x)
//                   over x < n − 1, and over the same pixels of ΔC = plus − minus
//   sums[kDeltaX] = Σ ΔC, sums[kDeltaX2] = Σ ΔC²;
//   likewise along y (kPlusY, kMinusY, kDeltaY, kDeltaY2) over y < n − 1.
// The scalar reference computes them in double; the SIMD kernel centres
// and multiplies in float, accumulates each column's values in float lanes
// over the rows and adds the lanes in double (means in double), so the two
// agree to float rounding of sums of n values (the terms are the products
// of a centred window's values; each sum is relative to Σ |term|).
// The kernel reads no pixel outside either window. Any n ≥ 2.
enum CorrelationSum { kC0, kPlusX, kMinusX, kPlusY, kMinusY, kDeltaX, kDeltaX2, kDeltaY, kDeltaY2, kCorrelationSumCount };
void correlation_statistics_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                                 double* sums);

// The reference for correlation_statistics_sums: plain loops in double.
void scalar_correlation_statistics_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride,
                                        int n, double* sums);

// The lag products of the same contributions ΔC (the plus − minus above),
// for the variance of their sum (vector_uncertainty.h), at lags 1 and 2
// along the axis:
//   lags[kLagX1] = Σ ΔCx(y, x)·ΔCx(y, x + 1), lags[kLagX2] the same at x + 2
//                  (over the pairs within a row), likewise kLagY1, kLagY2
//                  along a column;
//   lags[kEndsY1] = Σ ΔCy over the first and the last row of ΔCy (y = 0
//                  and n − 2), lags[kEndsY2] over the first two and the
//                  last two;
//   lags[kMeanA], lags[kMeanB] the windows' means (for the ends along x,
//                  which the caller sums).
// Float products in lanes added in double, as above; no pixel read outside
// either window. Any n ≥ 4.
enum CorrelationLagSum { kLagX1, kLagX2, kLagY1, kLagY2, kEndsY1, kEndsY2, kMeanA, kMeanB, kCorrelationLagSumCount };
void correlation_lag_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                          double* lags);
void scalar_correlation_lag_sums(const float* a, std::size_t a_stride, const float* b, std::size_t b_stride, int n,
                                 double* lags);

// The most capable target the kernels may use (see choosing the target above).
enum class SimdLimit { kAuto, kAvx2, kSse4, kPortable };

// Parses a BOSFUSE_SIMD value; nullopt when it is not one of the above.
std::optional<SimdLimit> parse_simd_limit(std::string_view text);

// Caps the kernels' targets from now on, replacing an earlier cap. Not
// thread-safe against kernels running at the same time.
void limit_simd_targets(SimdLimit limit);

// Highway's name of the target the kernels run on now: "AVX3" (AVX-512),
// "AVX2", "SSE4", "SSSE3", "EMU128" or "SCALAR" (the last two portable).
std::string simd_target_name();

}  // namespace bosfuse::fusion
