// Filter and interpolation kernels: separable weighted sums and the window
// deformation's resampling.
// Highway compiles this file once per target: foreach_target.h includes it
// again for each, with HWY_NAMESPACE naming the target; the code after
// HWY_ONCE is compiled only once and dispatches between them (the target cap
// all kernel files share is in simd_kernels.cc).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fusion/simd_resampling.cc"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
// Must follow foreach_target.h.
// clang-format off
#include "hwy/highway.h"
#include "hwy/cache_control.h"
// clang-format on

#include "fusion/simd_kernels.h"

// After foreach_target.h too, so that each target sees them.
#include <algorithm>
#include <cmath>
#include <utility>

HWY_BEFORE_NAMESPACE();
namespace bosfuse::fusion {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Four vectors of outputs at a time: four independent chains of products
// hide the latency of each one's sum.
void WeightedSum(const double* const* inputs, int taps, const double* weights, std::size_t count, double* out) {
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t j = 0;
  for (; j + 4 * lanes <= count; j += 4 * lanes) {
    auto w = hn::Set(d, weights[0]);
    auto a0 = hn::Mul(w, hn::LoadU(d, inputs[0] + j)), a1 = hn::Mul(w, hn::LoadU(d, inputs[0] + j + lanes));
    auto a2 = hn::Mul(w, hn::LoadU(d, inputs[0] + j + 2 * lanes)), a3 = hn::Mul(w, hn::LoadU(d, inputs[0] + j + 3 * lanes));
    for (int k = 1; k < taps; ++k) {
      w = hn::Set(d, weights[k]);
      const double* in = inputs[k] + j;
      a0 = hn::MulAdd(w, hn::LoadU(d, in), a0);
      a1 = hn::MulAdd(w, hn::LoadU(d, in + lanes), a1);
      a2 = hn::MulAdd(w, hn::LoadU(d, in + 2 * lanes), a2);
      a3 = hn::MulAdd(w, hn::LoadU(d, in + 3 * lanes), a3);
    }
    hn::StoreU(a0, d, out + j);
    hn::StoreU(a1, d, out + j + lanes);
    hn::StoreU(a2, d, out + j + 2 * lanes);
    hn::StoreU(a3, d, out + j + 3 * lanes);
  }
  for (; j + lanes <= count; j += lanes) {
    auto sum = hn::Mul(hn::Set(d, weights[0]), hn::LoadU(d, inputs[0] + j));
    for (int k = 1; k < taps; ++k) sum = hn::MulAdd(hn::Set(d, weights[k]), hn::LoadU(d, inputs[k] + j), sum);
    hn::StoreU(sum, d, out + j);
  }
  for (; j < count; ++j) {
    double sum = weights[0] * inputs[0][j];
    for (int k = 1; k < taps; ++k) sum += weights[k] * inputs[k][j];
    out[j] = sum;
  }
}

// The reference's sum at one point, taps clamped to the image: the SIMD
// kernel's path for points whose taps cross the image edge.
HWY_INLINE float SampleClamped(const float* HWY_RESTRICT image, std::size_t stride, int cols, int rows, int taps,
                               int x0, int y0, const float* HWY_RESTRICT wx, const float* HWY_RESTRICT wy) {
  float total = 0;
  for (int j = 0; j < taps; ++j) {
    const float* row = image + static_cast<std::size_t>(std::clamp(y0 + j, 0, rows - 1)) * stride;
    float row_total = 0;
    for (int i = 0; i < taps; ++i) row_total += wx[i] * row[std::clamp(x0 + i, 0, cols - 1)];
    total += wy[j] * row_total;
  }
  return total;
}

// Across the taps of one point: each vector holds `lanes` neighbouring tap
// columns, their weights interpolated between two table entries, summed down
// the tap rows, then weighted and added across lanes. Points whose taps
// (rounded up to whole vectors) leave the image take the clamped scalar path.
template <class D>
HWY_INLINE void SampleSeparable(D d, const float* HWY_RESTRICT image, std::size_t stride, int cols, int rows,
                                const TabulatedKernel& kernel, const double* HWY_RESTRICT xs,
                                const double* HWY_RESTRICT ys, int count, float* HWY_RESTRICT out) {
  const int lanes = static_cast<int>(hn::Lanes(d));
  const int taps = kernel.taps, steps = kernel.steps, first = 1 - taps / 2;
  const int span = (taps + lanes - 1) / lanes * lanes;
  HWY_ALIGN float wx[16], wy[16];
  // In the last vector of a point's taps, lanes past the taps hold the next
  // table entry's weights and pixels the reference never reads: zeroing
  // the pixels' column sums removes both (not even an infinity there
  // reaches the sum).
  const auto last_chunk = hn::FirstN(d, static_cast<std::size_t>(taps - (span - lanes)));
  const auto weights_at = [&](double t, int i) {
    const double position = t * steps;
    const int e = HWY_MIN(static_cast<int>(position), steps - 1);
    const auto f = hn::Set(d, static_cast<float>(position - e));
    const float* a = kernel.weights + static_cast<std::size_t>(e) * taps + i;
    const auto va = hn::LoadU(d, a);
    return hn::MulAdd(f, hn::Sub(hn::LoadU(d, a + taps), va), va);
  };
  for (int k = 0; k < count; ++k) {
    const double fx = std::floor(xs[k]), fy = std::floor(ys[k]);
    const int x = static_cast<int>(fx) + first, y = static_cast<int>(fy) + first;
    for (int i = 0; i < taps; i += lanes) hn::Store(weights_at(ys[k] - fy, i), d, wy + i);
    if (x < 0 || y < 0 || x + span > cols || y + taps > rows) {
      // The weights along x as the vectors below take them. Not
      // tabulated_weights: compiled for the baseline CPU it rounds
      // a + f·(b − a) twice, but where the compiler inlines it here, into an
      // AVX2 or AVX-512 function, it may fuse that into one multiply-add — and
      // whether it inlines depends on the rest of this file, so unrelated
      // edits moved the edge pixels of every warp (by ~1e-7) and every field
      // after them.
      for (int i = 0; i < taps; i += lanes) hn::Store(weights_at(xs[k] - fx, i), d, wx + i);
      out[k] = SampleClamped(image, stride, cols, rows, taps, x, y, wx, wy);
      continue;
    }
    const float* top = image + static_cast<std::size_t>(y) * stride + x;
    auto acc = hn::Zero(d);
    for (int i = 0; i < taps; i += lanes) {
      auto column = hn::Mul(hn::Set(d, wy[0]), hn::LoadU(d, top + i));
      for (int j = 1; j < taps; ++j) {
        column = hn::MulAdd(hn::Set(d, wy[j]), hn::LoadU(d, top + static_cast<std::size_t>(j) * stride + i), column);
      }
      if (i + lanes > taps) column = hn::IfThenElseZero(last_chunk, column);
      acc = hn::MulAdd(weights_at(xs[k] - fx, i), column, acc);
    }
    out[k] = hn::GetLane(hn::SumOfLanes(d, acc));
  }
}

#if HWY_TARGET != HWY_SCALAR
// r[i] (row i of an 8×8 block) becomes column i: unpacks within 128-bit
// blocks, then of 64-bit pairs, then the blocks combined.
template <class D>
HWY_INLINE void Transpose8x8(D d, hn::Vec<D>* r) {
  const hn::Repartition<double, D> dd;
  const auto lower64 = [&](hn::Vec<D> a, hn::Vec<D> b) {
    return hn::BitCast(d, hn::InterleaveLower(dd, hn::BitCast(dd, a), hn::BitCast(dd, b)));
  };
  const auto upper64 = [&](hn::Vec<D> a, hn::Vec<D> b) {
    return hn::BitCast(d, hn::InterleaveUpper(dd, hn::BitCast(dd, a), hn::BitCast(dd, b)));
  };
  const auto t0 = hn::InterleaveLower(d, r[0], r[1]), t1 = hn::InterleaveUpper(d, r[0], r[1]);
  const auto t2 = hn::InterleaveLower(d, r[2], r[3]), t3 = hn::InterleaveUpper(d, r[2], r[3]);
  const auto t4 = hn::InterleaveLower(d, r[4], r[5]), t5 = hn::InterleaveUpper(d, r[4], r[5]);
  const auto t6 = hn::InterleaveLower(d, r[6], r[7]), t7 = hn::InterleaveUpper(d, r[6], r[7]);
  const auto u0 = lower64(t0, t2), u1 = upper64(t0, t2), u2 = lower64(t1, t3), u3 = upper64(t1, t3);
  const auto u4 = lower64(t4, t6), u5 = upper64(t4, t6), u6 = lower64(t5, t7), u7 = upper64(t5, t7);
  r[0] = hn::ConcatLowerLower(d, u4, u0);
  r[1] = hn::ConcatLowerLower(d, u5, u1);
  r[2] = hn::ConcatLowerLower(d, u6, u2);
  r[3] = hn::ConcatLowerLower(d, u7, u3);
  r[4] = hn::ConcatUpperUpper(d, u4, u0);
  r[5] = hn::ConcatUpperUpper(d, u5, u1);
  r[6] = hn::ConcatUpperUpper(d, u6, u2);
  r[7] = hn::ConcatUpperUpper(d, u7, u3);
}

// Eight neighbouring points of a row, one per lane. Where the field is
// smooth (a window deformation's is) their taps start in one image row at
// consecutive columns, so each tap of all eight is one contiguous load and
// no point needs a sum across lanes. Each point's weights are its table
// rows interpolated (as in SampleSeparable), then transposed to one vector
// per tap. Summed as the scalar reference sums: each row of taps, then the
// rows weighted in order. False (nothing written) when the points are not
// so arranged or their taps leave the image. The taps are a template
// argument so that the tap loops unroll.
template <int kTaps, class D>
HWY_INLINE bool SampleEightAlongRow(D d, const float* HWY_RESTRICT image, std::size_t stride, int cols, int rows,
                                    const TabulatedKernel& kernel, const double* HWY_RESTRICT xs,
                                    const double* HWY_RESTRICT ys, float* HWY_RESTRICT out) {
  constexpr int kFirst = 1 - kTaps / 2;
  const int steps = kernel.steps;
  HWY_ALIGN int32_t entry_x[8], entry_y[8];
  HWY_ALIGN float frac_x[8], frac_y[8];
  // Positions in double, as the reference takes them: the whole pixel, the
  // table entry below the sub-pixel part and the fraction past it.
  const hn::CappedTag<double, 4> dd;
  const hn::Rebind<int32_t, decltype(dd)> di4;
  const hn::Rebind<float, decltype(dd)> df4;
  const int double_lanes = static_cast<int>(hn::Lanes(dd));
  const auto last_entry = hn::Set(dd, double(steps - 1)), vsteps = hn::Set(dd, double(steps));
  const auto split = [&](const double* p, int32_t* entry, float* frac, int i) {
    const auto v = hn::LoadU(dd, p + i);
    const auto floor = hn::Floor(v);
    const auto position = hn::Mul(hn::Sub(v, floor), vsteps);
    const auto e = hn::Min(hn::Floor(position), last_entry);
    hn::StoreU(hn::DemoteTo(di4, e), di4, entry + i);
    hn::StoreU(hn::DemoteTo(df4, hn::Sub(position, e)), df4, frac + i);
    return floor;
  };
  // The arrangement is checked on the whole pixels in double, in registers:
  // reading back eight ints stored as two halves stalls store forwarding.
  const double floor_x0 = std::floor(xs[0]), floor_y0 = std::floor(ys[0]);
  bool arranged = true;
  for (int i = 0; i < 8; i += double_lanes) {
    const auto fx = split(xs, entry_x, frac_x, i);
    const auto fy = split(ys, entry_y, frac_y, i);
    const auto next_column = hn::Eq(hn::Sub(fx, hn::Iota(dd, double(i))), hn::Set(dd, floor_x0));
    arranged = arranged && hn::AllTrue(dd, hn::And(next_column, hn::Eq(fy, hn::Set(dd, floor_y0))));
  }
  const int x0 = static_cast<int>(floor_x0) + kFirst, y0 = static_cast<int>(floor_y0) + kFirst;
  if (!arranged || x0 < 0 || y0 < 0 || x0 + 7 + kTaps > cols || y0 + kTaps > rows) return false;

  // Lanes past the taps hold the next entry's weights; those columns of the
  // transposed block are never used.
  hn::Vec<D> wx[8], wy[8];
  for (int k = 0; k < 8; ++k) {
    const float* a = kernel.weights + static_cast<std::size_t>(entry_x[k]) * kTaps;
    const auto va = hn::LoadU(d, a);
    wx[k] = hn::MulAdd(hn::Set(d, frac_x[k]), hn::Sub(hn::LoadU(d, a + kTaps), va), va);
    const float* b = kernel.weights + static_cast<std::size_t>(entry_y[k]) * kTaps;
    const auto vb = hn::LoadU(d, b);
    wy[k] = hn::MulAdd(hn::Set(d, frac_y[k]), hn::Sub(hn::LoadU(d, b + kTaps), vb), vb);
  }
  Transpose8x8(d, wx);
  Transpose8x8(d, wy);
  const float* top = image + static_cast<std::size_t>(y0) * stride + x0;
  auto total = hn::Zero(d);
  for (int j = 0; j < kTaps; ++j) {
    const float* row = top + static_cast<std::size_t>(j) * stride;
    auto row_total = hn::Mul(wx[0], hn::LoadU(d, row));
    for (int i = 1; i < kTaps; ++i) row_total = hn::MulAdd(wx[i], hn::LoadU(d, row + i), row_total);
    total = j == 0 ? hn::Mul(wy[0], row_total) : hn::MulAdd(wy[j], row_total, total);
  }
  hn::StoreU(total, d, out);
  return true;
}

// Points in groups of eight along the row where the targets have 8-lane
// float vectors (AVX2, AVX-512), the groups not so arranged one by one.
template <int kTaps, class D8>
HWY_INLINE int SampleInEightsOf(D8 d8, const float* image, std::size_t stride, int cols, int rows,
                                const TabulatedKernel& kernel, const double* x, const double* y, int count,
                                float* out) {
  int k = 0;
  for (; k + 8 <= count; k += 8) {
    if (!SampleEightAlongRow<kTaps>(d8, image, stride, cols, rows, kernel, x + k, y + k, out + k)) {
      SampleSeparable(d8, image, stride, cols, rows, kernel, x + k, y + k, 8, out + k);
    }
  }
  return k;
}

// How many points SampleInEightsOf took: none where the target's vectors
// are shorter than eight floats or the kernel is not one of ours.
template <class D8>
HWY_INLINE int SampleInEights(D8 d8, const float* image, std::size_t stride, int cols, int rows,
                              const TabulatedKernel& kernel, const double* x, const double* y, int count, float* out) {
  if constexpr (hn::MaxLanes(D8()) == 8) {
    if (hn::Lanes(d8) == 8) {
      switch (kernel.taps) {
        case 4:
          return SampleInEightsOf<4>(d8, image, stride, cols, rows, kernel, x, y, count, out);
        case 6:
          return SampleInEightsOf<6>(d8, image, stride, cols, rows, kernel, x, y, count, out);
        case 8:
          return SampleInEightsOf<8>(d8, image, stride, cols, rows, kernel, x, y, count, out);
        default:
          break;
      }
    }
  }
  return 0;
}
#endif

void SampleSeparablePoints(const float* image, std::size_t stride, int cols, int rows, const TabulatedKernel& kernel,
                           const double* x, const double* y, int count, float* out) {
  int k = 0;
#if HWY_TARGET != HWY_SCALAR
  k = SampleInEights(hn::CappedTag<float, 8>(), image, stride, cols, rows, kernel, x, y, count, out);
#endif
  if (kernel.taps <= 4) {
    SampleSeparable(hn::CappedTag<float, 4>(), image, stride, cols, rows, kernel, x + k, y + k, count - k, out + k);
  } else {
    SampleSeparable(hn::CappedTag<float, 8>(), image, stride, cols, rows, kernel, x + k, y + k, count - k, out + k);
  }
}


}  // namespace HWY_NAMESPACE
}  // namespace bosfuse::fusion
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <array>
#include <cmath>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(WeightedSum);
HWY_EXPORT(SampleSeparablePoints);

void weighted_sum(const double* const* inputs, int taps, const double* weights, std::size_t count, double* out) {
  HWY_DYNAMIC_DISPATCH(WeightedSum)(inputs, taps, weights, count, out);
}

void scalar_weighted_sum(const double* const* inputs, int taps, const double* weights, std::size_t count, double* out) {
  for (std::size_t j = 0; j < count; ++j) {
    double sum = weights[0] * inputs[0][j];
    for (int k = 1; k < taps; ++k) sum += weights[k] * inputs[k][j];
    out[j] = sum;
  }
}
void tabulated_weights(const TabulatedKernel& kernel, double t, float* weights) {
  const double position = t * kernel.steps;
  const int e = std::min(static_cast<int>(position), kernel.steps - 1);
  const float f = static_cast<float>(position - e);
  const float* a = kernel.weights + static_cast<std::size_t>(e) * kernel.taps;
  const float* b = a + kernel.taps;
  for (int k = 0; k < kernel.taps; ++k) weights[k] = a[k] + f * (b[k] - a[k]);
}

void sample_separable(const float* image, std::size_t stride, int cols, int rows, const TabulatedKernel& kernel,
                      const double* x, const double* y, int count, float* out) {
  HWY_DYNAMIC_DISPATCH(SampleSeparablePoints)(image, stride, cols, rows, kernel, x, y, count, out);
}

void scalar_sample_separable(const float* image, std::size_t stride, int cols, int rows, const TabulatedKernel& kernel,
                             const double* x, const double* y, int count, float* out) {
  const int taps = kernel.taps, first = 1 - taps / 2;
  for (int k = 0; k < count; ++k) {
    const double fx = std::floor(x[k]), fy = std::floor(y[k]);
    float wx[8], wy[8];
    tabulated_weights(kernel, x[k] - fx, wx);
    tabulated_weights(kernel, y[k] - fy, wy);
    const int ix = static_cast<int>(fx) + first, iy = static_cast<int>(fy) + first;
    const bool inside = ix >= 0 && iy >= 0 && ix + taps <= cols && iy + taps <= rows;
    float total = 0;
    for (int j = 0; j < taps; ++j) {
      const float* row = image + static_cast<std::size_t>(std::clamp(iy + j, 0, rows - 1)) * stride;
      float row_total = 0;
      if (inside) {
        for (int i = 0; i < taps; ++i) row_total += wx[i] * row[ix + i];
      } else {
        for (int i = 0; i < taps; ++i) row_total += wx[i] * row[std::clamp(ix + i, 0, cols - 1)];
      }
      total += wy[j] * row_total;
    }
    out[k] = total;
  }
}

}  // namespace bosfuse::fusion

#endif  // HWY_ONCE
