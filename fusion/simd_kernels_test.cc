#include "fusion/simd_kernels.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "fusion/field_warp.h"
#include "pipeline/simd_environment.h"

namespace bosfuse::fusion {
namespace {

// A centred reference window and a patch inside a wider buffer, so rows of
// the patch are not contiguous and its right edge is not the buffer's.
struct Inputs {
  int n, side;
  std::size_t stride;
  std::vector<float> reference, buffer;
  const float* patch() const { return buffer.data() + stride + 3; }
};

Inputs random_inputs(int n, int side, unsigned seed) {
  Inputs in{n, side, static_cast<std::size_t>(n + side - 1 + 7), {}, {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  in.reference.resize(static_cast<std::size_t>(n) * n);
  for (auto& a : in.reference) a = grey(rng) - 0.5f;
  in.buffer.resize(in.stride * (n + side + 1));
  for (auto& b : in.buffer) b = grey(rng);
  return in;
}

// Σ |a·b| for one shift: the scale float rounding is relative to (the
// products themselves may nearly cancel, the reference being centred).
double magnitude(const Inputs& in, int dx, int dy) {
  double sum = 0;
  for (int y = 0; y < in.n; ++y) {
    for (int x = 0; x < in.n; ++x) {
      sum += std::abs(double(in.reference[y * in.n + x]) * in.patch()[(y + dy) * in.stride + x + dx]);
    }
  }
  return sum;
}

void expect_kernel_matches_reference(int n, int side, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " side=" << side << " target=" << simd_target_name());
  const Inputs in = random_inputs(n, side, seed);
  const std::size_t count = static_cast<std::size_t>(side) * side;
  std::vector<double> simd(count, -1.0), reference(count, -2.0);
  accumulate_products(in.reference.data(), in.patch(), in.stride, n, side, simd.data());
  scalar_accumulate_products(in.reference.data(), in.patch(), in.stride, n, side, reference.data());
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      const std::size_t i = static_cast<std::size_t>(dy) * side + dx;
      ASSERT_NEAR(simd[i], reference[i], 1e-6 * magnitude(in, dx, dy)) << "dx=" << dx << " dy=" << dy;
    }
  }
}

void expect_all_sizes_match() {
  unsigned seed = 1;
  for (const int n : {1, 3, 8, 13, 16, 24, 32, 64}) {
    for (const int side : {1, 3, 4, 5, 7, 9, 11, 17}) expect_kernel_matches_reference(n, side, seed++);
  }
  expect_kernel_matches_reference(128, 5, seed++);
}

// `size` grey values of a bright image with `texture` contrast:
// 0.9 + texture·U(0, 1), drawn from `rng`.
std::vector<float> bright_values(std::size_t size, float texture, std::mt19937& rng) {
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  std::vector<float> values(size);
  for (auto& v : values) v = 0.9f + texture * grey(rng);
  return values;
}

// A window's mean and energy, the window centred, and its centred periodic
// tile, on a window inside a wider buffer (rows not contiguous). Bright
// windows with little texture are the hard case for the energy: Σ (x − mean)²
// is small against Σ x², so both kernels must centre before squaring.
void expect_window_kernels_match(int n, int radius, float texture, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " radius=" << radius << " texture=" << texture
                                  << " target=" << simd_target_name());
  const std::size_t stride = static_cast<std::size_t>(n) + 5;
  std::mt19937 rng(seed);
  const std::vector<float> buffer = bright_values(stride * (n + 2), texture, rng);
  const float* window = buffer.data() + stride + 2;
  double mean = -1, energy = -1, reference_mean = -2, reference_energy = -2;
  window_mean_energy(window, stride, n, &mean, &energy);
  scalar_window_mean_energy(window, stride, n, &reference_mean, &reference_energy);
  // Double rounding of sums of n² values of order 1.
  ASSERT_NEAR(mean, reference_mean, 1e-14);
  ASSERT_NEAR(energy, reference_energy, 1e-13 * n * n);
  if (n > 1) {
    ASSERT_GT(energy, 0.0);
  }

  const int p = n + 2 * radius;
  std::vector<float> tile(static_cast<std::size_t>(p) * p, -1.f), reference(tile.size(), -2.f);
  centred_periodic_tile(window, stride, n, radius, static_cast<float>(mean), tile.data());
  scalar_centred_periodic_tile(window, stride, n, radius, static_cast<float>(mean), reference.data());
  for (std::size_t i = 0; i < tile.size(); ++i) ASSERT_EQ(tile[i], reference[i]) << "at " << i % p << ", " << i / p;
  std::vector<float> centred(static_cast<std::size_t>(n) * n, -1.f), reference_centred(centred.size(), -2.f);
  centre_window(window, stride, n, mean, centred.data());
  scalar_centre_window(window, stride, n, mean, reference_centred.data());
  for (std::size_t i = 0; i < centred.size(); ++i) ASSERT_EQ(centred[i], reference_centred[i]) << "at " << i;
  // The tile's centre is the window itself, centred.
  ASSERT_EQ(tile[static_cast<std::size_t>(radius) * p + radius], window[0] - static_cast<float>(mean));
}

void expect_all_window_kernels_match() {
  unsigned seed = 200;
  for (const int n : {1, 2, 7, 8, 13, 16, 17, 32, 64, 128}) {
    for (const int radius : {0, 1, 2, 3, 6}) {
      if (radius >= n) continue;
      for (const float texture : {1.f, 1e-3f}) expect_window_kernels_match(n, radius, texture, seed++);
    }
  }
}

// The equal-windows correlation in one call against the kernels it
// replaces: a bright reference window and measurement window of `texture`
// contrast, in wider buffers. False (nothing written) is allowed: the SIMD
// kernel declines windows that are not one vector wide.
bool expect_equal_window_products_match(int n, int radius, float texture, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " radius=" << radius << " texture=" << texture
                                  << " target=" << simd_target_name());
  const std::size_t reference_stride = static_cast<std::size_t>(n) + 5, stride = static_cast<std::size_t>(n) + 3;
  std::mt19937 rng(seed);
  const std::vector<float> reference_buffer = bright_values(reference_stride * (n + 1), texture, rng);
  const std::vector<float> buffer = bright_values(stride * (n + 2), texture, rng);
  const float* reference = reference_buffer.data() + 3;
  const float* window = buffer.data() + stride + 1;
  double reference_mean = 0, reference_energy = 0;
  scalar_window_mean_energy(reference, reference_stride, n, &reference_mean, &reference_energy);
  const int side = 2 * radius + 1;
  std::vector<double> simd(static_cast<std::size_t>(side) * side, -1.0), expected(simd.size(), -2.0);
  double mean = -1, energy = -1, expected_mean = -2, expected_energy = -2;
  const bool applied = equal_window_products(reference, reference_stride, reference_mean, window, stride, n, radius,
                                             simd.data(), &mean, &energy);
  if (!applied) {
    for (const double v : simd) EXPECT_EQ(v, -1.0);
    EXPECT_EQ(mean, -1.0);
    return false;
  }
  scalar_equal_window_products(reference, reference_stride, reference_mean, window, stride, n, radius, expected.data(),
                               &expected_mean, &expected_energy);
  // Float sums of n values of order 1 per lane: the mean is off by a few
  // float roundings, a constant shift of the centred window that the
  // products over a whole period do not see.
  EXPECT_NEAR(mean, expected_mean, 1e-6 * expected_mean);
  EXPECT_NEAR(energy, expected_energy, 1e-5 * expected_energy);
  EXPECT_GT(energy, 0.0);
  // Float sums of n² products of values of order `texture`.
  const double tolerance = 1e-6 * n * n * texture * texture;
  for (std::size_t i = 0; i < simd.size(); ++i) {
    EXPECT_NEAR(simd[i], expected[i], tolerance) << "dx=" << i % side << " dy=" << i / side;
  }
  return true;
}

// On every target but the one-lane SCALAR one some window width is one
// vector (4, 8 or 16 floats), so the SIMD kernel must have been tested.
void expect_all_equal_window_products_match() {
  unsigned seed = 400;
  int applied = 0;
  for (const int n : {4, 8, 16, 32}) {
    for (const int radius : {0, 1, 2, 3}) {
      if (2 * radius >= n) continue;
      for (const float texture : {1.f, 1e-3f})
        applied += expect_equal_window_products_match(n, radius, texture, seed++);
    }
  }
  if (simd_target_name() != "SCALAR") {
    EXPECT_GT(applied, 0);
  }
}

// Box sums of a patch inside a wider buffer, bright and of little texture
// (where the energy squares − sums²/n² is a small difference).
void expect_patch_box_sums_match(int n, int radius, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " radius=" << radius << " target=" << simd_target_name());
  const int p = n + 2 * radius, side = 2 * radius + 1;
  const std::size_t stride = static_cast<std::size_t>(p) + 3;
  std::mt19937 rng(seed);
  const std::vector<float> buffer = bright_values(stride * (p + 1), 1e-3f, rng);
  const float* patch = buffer.data() + stride + 2;
  const auto count = static_cast<std::size_t>(side) * side;
  std::vector<double> sums(count, -1), squares(count, -1), expected_sums(count, -2), expected_squares(count, -2);
  std::vector<double> scratch(2 * static_cast<std::size_t>(side) * p);
  patch_box_sums(patch, stride, p, n, scratch.data(), sums.data(), squares.data());
  scalar_patch_box_sums(patch, stride, p, n, expected_sums.data(), expected_squares.data());
  // Double rounding of sliding sums of values of order 1; the energies
  // (about 1e-7·n² here) keep at least six digits.
  for (std::size_t i = 0; i < count; ++i) {
    ASSERT_NEAR(sums[i], expected_sums[i], 1e-13 * n * n) << "at " << i % side << ", " << i / side;
    ASSERT_NEAR(squares[i], expected_squares[i], 1e-13 * n * n) << "at " << i % side << ", " << i / side;
    const double energy = squares[i] - sums[i] * sums[i] / (n * n);
    const double expected_energy = expected_squares[i] - expected_sums[i] * expected_sums[i] / (n * n);
    ASSERT_NEAR(energy, expected_energy, 1e-6 * expected_energy);
  }
}

void expect_all_patch_box_sums_match() {
  unsigned seed = 600;
  for (const int n : {1, 3, 8, 16, 17, 32, 64}) {
    for (const int radius : {0, 1, 2, 4, 9}) expect_patch_box_sums_match(n, radius, seed++);
  }
}

// The box sums on whatever target: every one does the same operations in the
// same order (patch rows of two to six vectors in registers, others through
// memory), so a field does not depend on the CPU it was evaluated on.
// Pixels of magnitudes nine decades apart, so that the sums round and their
// order shows (sums of similar floats are exact in double in any order).
std::vector<float> pixels_of_mixed_magnitude(std::size_t size, std::mt19937& rng) {
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  const float scales[] = {1.f, 1e-4f, 1e-9f};
  std::vector<float> values(size);
  for (auto& v : values) v = scales[rng() % 3] * grey(rng);
  return values;
}

struct BoxSums {
  std::vector<double> sums, squares;
};

std::vector<BoxSums> box_sums_of_every_size() {
  std::vector<BoxSums> all;
  unsigned seed = 700;
  for (const int n : {3, 8, 16, 32}) {
    for (const int radius : {1, 2, 4, 8, 9}) {
      const int p = n + 2 * radius, side = 2 * radius + 1;
      const std::size_t stride = static_cast<std::size_t>(p) + 5;
      std::mt19937 rng(seed++);
      const std::vector<float> buffer = pixels_of_mixed_magnitude(stride * (p + 1), rng);
      const auto count = static_cast<std::size_t>(side) * side;
      BoxSums out{std::vector<double>(count), std::vector<double>(count)};
      std::vector<double> scratch(2 * static_cast<std::size_t>(side) * p);
      patch_box_sums(buffer.data() + 1, stride, p, n, scratch.data(), out.sums.data(), out.squares.data());
      all.push_back(std::move(out));
    }
  }
  return all;
}

// The search-area normalisation on the box sums of real patches: textured,
// bright and nearly flat, and flat (energy 0, below the floor), with a
// textured and a flat reference; every count of shifts from one to past a
// 512-bit vector's multiple. Exactly equal: the same IEEE operations.
void expect_normalisations_match(std::size_t count, float texture, double reference_energy, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "count=" << count << " texture=" << texture
                                  << " reference_energy=" << reference_energy << " target=" << simd_target_name());
  constexpr int kWindow = 16;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> product(-1, 1);
  std::vector<double> sums(count), squares(count), products(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::vector<float> box = bright_values(kWindow * kWindow, texture, rng);
    double scratch[2 * kWindow];  // side 1: one row of column sums per table
    patch_box_sums(box.data(), kWindow, kWindow, kWindow, scratch, &sums[i], &squares[i]);
    products[i] = product(rng) * std::sqrt(std::max(reference_energy, 0.0) * 1e-3);
  }
  constexpr double kMinEnergy = 1e-12;
  // Energies just under and just over the floor (sums 0: energy = squares).
  const std::size_t under = count / 2, over = count - 1;
  sums[under] = sums[over] = 0;
  squares[under] = 0.5 * kMinEnergy;
  if (over != under) squares[over] = 2 * kMinEnergy;
  std::vector<double> out(count + 1, -7), expected(count + 1, -7);
  normalise_by_energies(products.data(), sums.data(), squares.data(), count, kWindow * kWindow, reference_energy,
                        kMinEnergy, out.data());
  scalar_normalise_by_energies(products.data(), sums.data(), squares.data(), count, kWindow * kWindow, reference_energy,
                               kMinEnergy, expected.data());
  for (std::size_t i = 0; i < count; ++i) ASSERT_EQ(out[i], expected[i]) << "shift " << i;
  ASSERT_EQ(out[count], -7) << "written past the last shift";
  ASSERT_EQ(out[under], 0.0) << "an energy under the floor is flat";
  if (texture == 0.f || reference_energy < kMinEnergy) {
    for (std::size_t i = 0; i < count; ++i) {
      if (i != over || reference_energy < kMinEnergy) {
        ASSERT_EQ(out[i], 0.0) << "a flat pair correlates as 0, shift " << i;
      }
    }
  }
}

// Sets of eight in medians_of_eight's layout with every kind of order:
// random values, ties, zeros of both signs; every count from none to past
// two 512-bit vectors, inside a wider stride. Equal exactly: exact operations.
void expect_medians_of_eight_match() {
  std::mt19937 rng(1200);
  std::uniform_real_distribution<double> value(-2, 2);
  std::uniform_int_distribution<int> small(-2, 2);
  for (std::size_t count = 0; count <= 19; ++count) {
    SCOPED_TRACE(testing::Message() << "count=" << count << " target=" << simd_target_name());
    const std::size_t stride = count + 3;
    std::vector<double> values(8 * stride), centres(count);
    for (std::size_t i = 0; i < values.size(); ++i) {
      values[i] = i % 3 == 0 ? double(small(rng)) : i % 7 == 0 ? -0.0 : value(rng);
    }
    for (auto& c : centres) c = value(rng);
    std::vector<double> medians(count + 1, -9), expected(count + 1, -9);
    medians_of_eight(values.data(), stride, count, medians.data());
    scalar_medians_of_eight(values.data(), stride, count, expected.data());
    ASSERT_EQ(medians, expected);
    for (std::size_t j = 0; j < count; ++j) {
      std::vector<double> set;
      for (std::size_t k = 0; k < 8; ++k) set.push_back(values[k * stride + j]);
      std::nth_element(set.begin(), set.begin() + 4, set.end());
      const double upper = set[4], lower = *std::max_element(set.begin(), set.begin() + 4);
      ASSERT_EQ(expected[j], 0.5 * (lower + upper)) << "set " << j;
    }
    std::vector<double> residuals(count + 1, -9), expected_residuals(count + 1, -9);
    normalised_residuals_of_eight(values.data(), stride, count, centres.data(), 0.1, residuals.data());
    scalar_normalised_residuals_of_eight(values.data(), stride, count, centres.data(), 0.1, expected_residuals.data());
    ASSERT_EQ(residuals, expected_residuals);
  }
}

// Rows of a separable filter, along a row (inputs overlapping, one element
// apart) and across rows: every count up to four vectors of lanes and past
// them, 1 to 13 taps. Σ|w·x| bounds the rounding of each sum.
void expect_weighted_sums_match() {
  std::mt19937 rng(1300);
  std::uniform_real_distribution<double> value(-3, 3);
  for (const int taps : {1, 2, 5, 13}) {
    for (std::size_t count = 0; count <= 37; ++count) {
      SCOPED_TRACE(testing::Message() << "taps=" << taps << " count=" << count << " target=" << simd_target_name());
      std::vector<double> weights(static_cast<std::size_t>(taps)), row(count + taps), out(count + 1, -9),
          expected(count + 1, -9);
      for (double& w : weights) w = value(rng);
      for (double& x : row) x = value(rng);
      std::vector<const double*> along(static_cast<std::size_t>(taps)), across(static_cast<std::size_t>(taps));
      std::vector<std::vector<double>> rows(static_cast<std::size_t>(taps), std::vector<double>(count));
      for (int k = 0; k < taps; ++k) {
        along[k] = row.data() + k;
        for (double& x : rows[k]) x = value(rng);
        across[k] = rows[k].data();
      }
      for (const auto& inputs : {along, across}) {
        weighted_sum(inputs.data(), taps, weights.data(), count, out.data());
        scalar_weighted_sum(inputs.data(), taps, weights.data(), count, expected.data());
        for (std::size_t j = 0; j < count; ++j) {
          double magnitude = 0;
          for (int k = 0; k < taps; ++k) magnitude += std::abs(weights[k] * inputs[k][j]);
          ASSERT_NEAR(out[j], expected[j], 1e-15 * taps * magnitude) << "output " << j;
        }
        ASSERT_EQ(out[count], -9) << "nothing written past count";
      }
    }
  }
}

void expect_all_normalisations_match() {
  unsigned seed = 900;
  for (const std::size_t count : {1, 7, 8, 9, 16, 25, 81, 83}) {
    for (const float texture : {0.1f, 1e-3f, 0.f}) {
      for (const double reference_energy : {0.5, 1e-14}) {
        expect_normalisations_match(count, texture, reference_energy, seed++);
      }
    }
  }
}

// The window deformation's sampling: a random image inside a wider buffer,
// and the points of a region reaching past every edge of the image, moved
// by a random smooth displacement field (up to ±4 px).
struct SamplingInputs {
  int cols, rows;
  TabulatedKernel kernel;
  std::size_t stride;
  std::vector<float> buffer;
  std::vector<double> x, y;
  const float* image() const { return buffer.data() + 2 * stride + 5; }
  int count() const { return static_cast<int>(x.size()); }
};

// `smooth`: a gentle field instead (sub-pixel shifts varying by a few
// thousandths of a pixel per pixel), as window deformation has, where
// neighbouring points' taps start at consecutive columns of one row: the
// kernel's path for points in groups.
SamplingInputs random_sampling(int cols, int rows, Interpolator interpolator, unsigned seed, bool smooth = false) {
  SamplingInputs in{cols, rows, interpolation_kernel(interpolator), static_cast<std::size_t>(cols + 11), {}, {}, {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  in.buffer.resize(in.stride * (rows + 4));
  for (auto& b : in.buffer) b = static_cast<float>(unit(rng));
  // A sum of two random plane waves per component: smooth, and over the
  // region both sub-pixel positions and whole-pixel offsets vary.
  double a[2][2], k[2][2][2], phase[2][2];
  for (int c = 0; c < 2; ++c) {
    for (int w = 0; w < 2; ++w) {
      a[c][w] = 2.0 * unit(rng);
      k[c][w][0] = 0.3 * (unit(rng) - 0.5);
      k[c][w][1] = 0.3 * (unit(rng) - 0.5);
      phase[c][w] = 6.3 * unit(rng);
    }
  }
  const auto displacement = [&](int c, double x, double y) {
    double d = 0;
    for (int w = 0; w < 2; ++w) d += a[c][w] * std::sin(k[c][w][0] * x + k[c][w][1] * y + phase[c][w]);
    return d;
  };
  const double u0 = 2.0 * unit(rng) - 1.0, v0 = 2.0 * unit(rng) - 1.0;
  for (int y = -9; y < rows + 9; ++y) {
    for (int x = -9; x < cols + 9; ++x) {
      if (smooth) {
        in.x.push_back(x + u0 + 0.004 * x - 0.002 * y);
        in.y.push_back(y + v0 + 0.003 * x + 0.001 * y);
      } else {
        in.x.push_back(x + displacement(0, x, y));
        in.y.push_back(y + displacement(1, x, y));
      }
    }
  }
  // Whole-pixel positions too (sub-pixel part 0, the table's first entry).
  in.x.push_back(3.0);
  in.y.push_back(2.0);
  return in;
}

// Σ |wx·wy·pixel| over the taps of point k, clamped as the kernels clamp.
double sampling_magnitude(const SamplingInputs& in, int k) {
  const int taps = in.kernel.taps;
  const double fx = std::floor(in.x[k]), fy = std::floor(in.y[k]);
  float wx[8], wy[8];
  tabulated_weights(in.kernel, in.x[k] - fx, wx);
  tabulated_weights(in.kernel, in.y[k] - fy, wy);
  const int x0 = static_cast<int>(fx) + 1 - taps / 2, y0 = static_cast<int>(fy) + 1 - taps / 2;
  double sum = 0;
  for (int j = 0; j < taps; ++j) {
    const float* row = in.image() + static_cast<std::size_t>(std::clamp(y0 + j, 0, in.rows - 1)) * in.stride;
    for (int i = 0; i < taps; ++i) sum += std::abs(double(wx[i]) * wy[j] * row[std::clamp(x0 + i, 0, in.cols - 1)]);
  }
  return sum;
}

void expect_sampling_matches_reference(int cols, int rows, Interpolator interpolator, unsigned seed,
                                       bool smooth = false) {
  SCOPED_TRACE(testing::Message() << cols << "x" << rows << " interpolator=" << static_cast<int>(interpolator)
                                  << " smooth=" << smooth << " target=" << simd_target_name());
  const SamplingInputs in = random_sampling(cols, rows, interpolator, seed, smooth);
  std::vector<float> simd(in.x.size(), -1.f), reference(in.x.size(), -2.f);
  sample_separable(in.image(), in.stride, cols, rows, in.kernel, in.x.data(), in.y.data(), in.count(), simd.data());
  scalar_sample_separable(in.image(), in.stride, cols, rows, in.kernel, in.x.data(), in.y.data(), in.count(),
                          reference.data());
  for (int k = 0; k < in.count(); ++k) {
    ASSERT_NEAR(simd[k], reference[k], 1e-6 * sampling_magnitude(in, k))
        << "point " << k << " at " << in.x[k] << ", " << in.y[k];
  }
}

void expect_all_samplings_match() {
  unsigned seed = 100;
  for (const auto interpolator : {Interpolator::kCubic, Interpolator::kLanczos3, Interpolator::kLanczos4}) {
    for (const auto& [cols, rows] : {std::pair{67, 41}, std::pair{8, 8}, std::pair{3, 5}, std::pair{1, 1}}) {
      expect_sampling_matches_reference(cols, rows, interpolator, seed++);
      expect_sampling_matches_reference(cols, rows, interpolator, seed++, true);
    }
  }
}

// The whole warp against its reference, on a random image and a random
// grid field, over a region past the image's corner. Image values are in
// [0, 1) and Σ|w| ≤ 1.5 per axis for these kernels, so Σ|w·pixel| ≤ 2.25.
void expect_warp_matches_reference() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  cv::Mat image(90, 130, CV_32F);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) image.at<float>(y, x) = unit(rng);
  }
  GridField field{{4, 6, 16, 7, 9}, cv::Mat(7, 9, CV_64F), cv::Mat(7, 9, CV_64F)};
  for (int r = 0; r < 7; ++r) {
    for (int c = 0; c < 9; ++c) {
      field.u_px.at<double>(r, c) = 3.0 * std::sin(0.4 * c + 0.3 * r) + 0.1 * unit(rng);
      field.v_px.at<double>(r, c) = 2.5 * std::cos(0.35 * r - 0.2 * c) + 0.1 * unit(rng);
    }
  }
  for (const auto interpolator : {Interpolator::kCubic, Interpolator::kLanczos3, Interpolator::kLanczos4}) {
    for (const cv::Rect region : {cv::Rect(-7, -5, 60, 40), cv::Rect(80, 60, 60, 40), cv::Rect(0, 0, 130, 90)}) {
      SCOPED_TRACE(testing::Message() << "interpolator=" << static_cast<int>(interpolator) << " region=" << region
                                      << " target=" << simd_target_name());
      const cv::Mat simd = warp_region(image, field, region, interpolator);
      const cv::Mat reference = scalar_warp_region(image, field, region, interpolator);
      ASSERT_EQ(simd.size(), reference.size());
      for (int y = 0; y < simd.rows; ++y) {
        for (int x = 0; x < simd.cols; ++x) {
          ASSERT_NEAR(simd.at<float>(y, x), reference.at<float>(y, x), 2.25e-6) << "x=" << x << " y=" << y;
        }
      }
    }
  }
}

// An n×n window of grey levels offset + U(0, 1) at the end of `buffer`
// (rows `stride` apart), NaN around it: a read outside the window shows.
float* nan_fenced_window(std::vector<float>& buffer, std::size_t stride, int n, float offset, std::mt19937& rng) {
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  buffer.assign(stride * (n + 2), std::nanf(""));
  float* window = buffer.data() + buffer.size() - (static_cast<std::size_t>(n - 1) * stride + n);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) window[y * stride + x] = offset + grey(rng);
  }
  return window;
}

// The mean of such a window, in double.
double nan_fenced_window_mean(const float* window, std::size_t stride, int n) {
  double sum = 0;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) sum += window[y * stride + x];
  }
  return sum / (double(n) * n);
}

// Two n×n windows inside wider buffers, ending at a buffer's last float
// and surrounded by NaN, so a read past either window shows (as NaN here,
// under ASan as an overflow); the sums against the reference, each within
// 1e-5 of the magnitude of its terms (Σ |term|; for the squares, Σ of the
// squared sum of |plus| and |minus|, the scale of ΔC's float rounding).
void expect_correlation_sums_match(int n, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " target=" << simd_target_name());
  std::mt19937 rng(seed);
  const std::size_t stride = static_cast<std::size_t>(n) + 5;
  std::vector<float> buffer_a, buffer_b;
  const float* a = nan_fenced_window(buffer_a, stride, n, 0.4f, rng);
  const float* b = nan_fenced_window(buffer_b, stride, n, 0.6f, rng);
  double simd[kCorrelationSumCount], reference[kCorrelationSumCount];
  correlation_statistics_sums(a, stride, b, stride, n, simd);
  scalar_correlation_statistics_sums(a, stride, b, stride, n, reference);
  double magnitude[kCorrelationSumCount] = {};
  const auto centred = [&](const float* w, int y, int x, double mean) { return w[y * stride + x] - mean; };
  const double mean_a = nan_fenced_window_mean(a, stride, n), mean_b = nan_fenced_window_mean(b, stride, n);
  const auto add = [&](CorrelationSum plus_i, CorrelationSum minus_i, CorrelationSum delta_i, CorrelationSum square_i,
                       double plus, double minus) {
    magnitude[plus_i] += std::abs(plus);
    magnitude[minus_i] += std::abs(minus);
    magnitude[delta_i] += std::abs(plus) + std::abs(minus);
    magnitude[square_i] += (std::abs(plus) + std::abs(minus)) * (std::abs(plus) + std::abs(minus));
  };
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const double a0 = centred(a, y, x, mean_a), b0 = centred(b, y, x, mean_b);
      magnitude[kC0] += std::abs(a0 * b0);
      if (x + 1 < n) {
        add(kPlusX, kMinusX, kDeltaX, kDeltaX2, a0 * centred(b, y, x + 1, mean_b), centred(a, y, x + 1, mean_a) * b0);
      }
      if (y + 1 < n) {
        add(kPlusY, kMinusY, kDeltaY, kDeltaY2, a0 * centred(b, y + 1, x, mean_b), centred(a, y + 1, x, mean_a) * b0);
      }
    }
  }
  for (int k = 0; k < kCorrelationSumCount; ++k) {
    ASSERT_TRUE(std::isfinite(simd[k])) << "sum " << k;
    ASSERT_NEAR(simd[k], reference[k], 1e-5 * magnitude[k]) << "sum " << k;
  }
}

// The lag products of the contributions: the kernel against the scalar
// reference, to 1e-5 of the sum of |plus| + |minus| products (the scale of
// the contributions' float rounding).
void expect_correlation_lag_sums_match(int n, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " target=" << simd_target_name());
  std::mt19937 rng(seed);
  const std::size_t stride = static_cast<std::size_t>(n) + 3;
  std::vector<float> buffer_a, buffer_b;
  const float* a = nan_fenced_window(buffer_a, stride, n, 0.4f, rng);
  const float* b = nan_fenced_window(buffer_b, stride, n, 0.6f, rng);
  double simd[kCorrelationLagSumCount], reference[kCorrelationLagSumCount];
  correlation_lag_sums(a, stride, b, stride, n, simd);
  scalar_correlation_lag_sums(a, stride, b, stride, n, reference);
  // |plus| + |minus| of each contribution, centred on the windows' means.
  const double mean_a = nan_fenced_window_mean(a, stride, n), mean_b = nan_fenced_window_mean(b, stride, n);
  const auto size = [&](int y0, int x0, int y1, int x1) {
    return std::abs((a[y0 * stride + x0] - mean_a) * (b[y1 * stride + x1] - mean_b)) +
           std::abs((a[y1 * stride + x1] - mean_a) * (b[y0 * stride + x0] - mean_b));
  };
  double magnitude[kCorrelationLagSumCount] = {};
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x + 1 < n; ++x) {
      if (x + 2 < n) magnitude[kLagX1] += size(y, x, y, x + 1) * size(y, x + 1, y, x + 2);
      if (x + 3 < n) magnitude[kLagX2] += size(y, x, y, x + 1) * size(y, x + 2, y, x + 3);
    }
  }
  for (int y = 0; y + 1 < n; ++y) {
    for (int x = 0; x < n; ++x) {
      if (y + 2 < n) magnitude[kLagY1] += size(y, x, y + 1, x) * size(y + 1, x, y + 2, x);
      if (y + 3 < n) magnitude[kLagY2] += size(y, x, y + 1, x) * size(y + 2, x, y + 3, x);
      magnitude[kEndsY1] += size(y, x, y + 1, x);  // every row: a bound of the ends' magnitude
    }
  }
  magnitude[kEndsY2] = magnitude[kEndsY1];
  magnitude[kMeanA] = 1 + std::abs(mean_a), magnitude[kMeanB] = 1 + std::abs(mean_b);
  for (int k = 0; k < kCorrelationLagSumCount; ++k) {
    ASSERT_TRUE(std::isfinite(simd[k])) << "sum " << k;
    ASSERT_NEAR(simd[k], reference[k], 1e-5 * magnitude[k]) << "sum " << k;
  }
}

void expect_all_correlation_sums_match() {
  unsigned seed = 300;
  for (const int n : {2, 3, 4, 5, 8, 9, 12, 13, 16, 17, 24, 31, 32, 48, 64}) expect_correlation_sums_match(n, seed++);
  for (const int n : {4, 5, 8, 10, 11, 12, 13, 16, 17, 24, 31, 32, 48, 64}) expect_correlation_lag_sums_match(n, seed++);
}

// Every test leaves the dispatch as it found it: no cap, no mock.
class SimdKernels : public testing::Test {
 protected:
  void TearDown() override {
    hwy::SetSupportedTargetsForTest(0);
    limit_simd_targets(SimdLimit::kAuto);
  }
};

TEST_F(SimdKernels, MatchTheScalarReference) {
  expect_all_sizes_match();
  expect_all_window_kernels_match();
  expect_all_equal_window_products_match();
  expect_all_patch_box_sums_match();
  expect_all_normalisations_match();
  expect_medians_of_eight_match();
  expect_weighted_sums_match();
  expect_all_correlation_sums_match();
}

TEST_F(SimdKernels, SamplingMatchesTheScalarReference) {
  expect_all_samplings_match();
  expect_warp_matches_reference();
}

TEST_F(SimdKernels, SamplingMatchesTheScalarReferenceOnEveryTargetOfThisCpu) {
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_EQ(simd_target_name(), hwy::TargetName(target));
    expect_all_samplings_match();
    expect_warp_matches_reference();
  }
}

TEST_F(SimdKernels, MatchTheScalarReferenceOnEveryTargetOfThisCpu) {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  for (const std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_EQ(simd_target_name(), hwy::TargetName(target));
    expect_all_sizes_match();
    expect_all_window_kernels_match();
    expect_all_equal_window_products_match();
    expect_all_patch_box_sums_match();
    expect_all_normalisations_match();
    expect_medians_of_eight_match();
    expect_weighted_sums_match();
    expect_all_correlation_sums_match();
  }
}

TEST_F(SimdKernels, BoxSumsAreTheSameOnEveryTargetOfThisCpu) {
  limit_simd_targets(SimdLimit::kPortable);
  const std::vector<BoxSums> portable = box_sums_of_every_size();
  limit_simd_targets(SimdLimit::kAuto);
  for (const std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(simd_target_name());
    const std::vector<BoxSums> sums = box_sums_of_every_size();
    ASSERT_EQ(sums.size(), portable.size());
    for (std::size_t i = 0; i < sums.size(); ++i) {
      EXPECT_EQ(sums[i].sums, portable[i].sums) << "patch " << i;
      EXPECT_EQ(sums[i].squares, portable[i].squares) << "patch " << i;
    }
  }
}

TEST_F(SimdKernels, TheEnvironmentForcesThePortableTarget) {
  ASSERT_EQ(setenv("BOSFUSE_SIMD", "portable", 1), 0);
  pipeline::apply_simd_environment();
  const std::string name = simd_target_name();
  EXPECT_TRUE(name == "SCALAR" || name == "EMU128") << name;
  expect_all_sizes_match();
  expect_all_window_kernels_match();
  expect_all_equal_window_products_match();
  expect_all_patch_box_sums_match();
  expect_all_normalisations_match();
  expect_medians_of_eight_match();
  expect_weighted_sums_match();
  expect_all_samplings_match();
  expect_warp_matches_reference();
  ASSERT_EQ(unsetenv("BOSFUSE_SIMD"), 0);
  pipeline::apply_simd_environment();
  EXPECT_EQ(simd_target_name(), hwy::TargetName(hwy::SupportedAndGeneratedTargets().front()));
}

TEST_F(SimdKernels, ALimitCapsTheTarget) {
  limit_simd_targets(SimdLimit::kSse4);
  const std::string name = simd_target_name();
  EXPECT_NE(name, "AVX2");
  EXPECT_NE(name, "AVX3");
  expect_all_sizes_match();
  expect_all_samplings_match();
}

TEST(SimdLimit, ParsesTheEnvironmentValues) {
  EXPECT_EQ(parse_simd_limit(""), SimdLimit::kAuto);
  EXPECT_EQ(parse_simd_limit("auto"), SimdLimit::kAuto);
  EXPECT_EQ(parse_simd_limit("avx2"), SimdLimit::kAvx2);
  EXPECT_EQ(parse_simd_limit("sse4"), SimdLimit::kSse4);
  EXPECT_EQ(parse_simd_limit("portable"), SimdLimit::kPortable);
  EXPECT_EQ(parse_simd_limit("AVX2"), std::nullopt);
  EXPECT_EQ(parse_simd_limit("neon"), std::nullopt);
}

}  // namespace
}  // namespace bosfuse::fusion
