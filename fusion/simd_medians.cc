// Median kernels: medians of eight and the normalised median test's residuals.
// Highway compiles this file once per target: foreach_target.h includes it
// again for each, with HWY_NAMESPACE naming the target; the code after
// HWY_ONCE is compiled only once and dispatches between them (the target cap
// all kernel files share is in simd_kernels.cc).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fusion/simd_medians.cc"
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

// Sorts each lane's eight values with the 19 compare-exchanges of the
// optimal network (Knuth, TAOCP 5.3.4), one set per lane.
template <class D>
HWY_INLINE void SortEight(D /*d*/, hn::Vec<D>* v) {
  static constexpr int kPairs[19][2] = {{0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}, {0, 1}, {2, 3},
                                        {4, 5}, {6, 7}, {2, 4}, {3, 5}, {1, 4}, {3, 6}, {1, 2}, {3, 4}, {5, 6}};
  // Unrolled, the eight vectors stay in registers.
#pragma GCC unroll 19
  for (const auto& [i, j] : kPairs) {
    const auto low = hn::Min(v[i], v[j]);
    v[j] = hn::Max(v[i], v[j]);
    v[i] = low;
  }
}

// Loads the eight values of the sets j … j + lanes − 1 and returns their
// medians, leaving them sorted in `v`.
template <class D>
HWY_INLINE hn::Vec<D> MedianOfEight(D d, const double* HWY_RESTRICT values, std::size_t stride, std::size_t j,
                                    hn::Vec<D>* v) {
  for (int k = 0; k < 8; ++k) v[k] = hn::LoadU(d, values + k * stride + j);
  SortEight(d, v);
  return hn::Mul(hn::Set(d, 0.5), hn::Add(v[3], v[4]));
}

void MediansOfEight(const double* values, std::size_t stride, std::size_t count, double* medians) {
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t j = 0;
  for (; j + lanes <= count; j += lanes) {
    hn::Vec<decltype(d)> v[8];
    hn::StoreU(MedianOfEight(d, values, stride, j, v), d, medians + j);
  }
  scalar_medians_of_eight(values + j, stride, count - j, medians + j);
}
void NormalisedResidualsOfEight(const double* values, std::size_t stride, std::size_t count, const double* centres,
                                double epsilon, double* residuals) {
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t j = 0;
  for (; j + lanes <= count; j += lanes) {
    hn::Vec<decltype(d)> v[8];
    const auto median = MedianOfEight(d, values, stride, j, v);
    for (auto& value : v) value = hn::Abs(hn::Sub(value, median));
    SortEight(d, v);
    const auto spread = hn::Mul(hn::Set(d, 0.5), hn::Add(v[3], v[4]));
    const auto distance = hn::Abs(hn::Sub(hn::LoadU(d, centres + j), median));
    hn::StoreU(hn::Div(distance, hn::Add(spread, hn::Set(d, epsilon))), d, residuals + j);
  }
  scalar_normalised_residuals_of_eight(values + j, stride, count - j, centres + j, epsilon, residuals + j);
}

}  // namespace HWY_NAMESPACE
}  // namespace bosfuse::fusion
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <array>
#include <cmath>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(MediansOfEight);
HWY_EXPORT(NormalisedResidualsOfEight);

void medians_of_eight(const double* values, std::size_t stride, std::size_t count, double* medians) {
  HWY_DYNAMIC_DISPATCH(MediansOfEight)(values, stride, count, medians);
}

namespace {

// Set j of medians_of_eight's layout, sorted.
std::array<double, 8> sorted_set(const double* values, std::size_t stride, std::size_t j) {
  std::array<double, 8> set;
  for (std::size_t k = 0; k < 8; ++k) set[k] = values[k * stride + j];
  std::sort(set.begin(), set.end());
  return set;
}

}  // namespace

void scalar_medians_of_eight(const double* values, std::size_t stride, std::size_t count, double* medians) {
  for (std::size_t j = 0; j < count; ++j) {
    const std::array<double, 8> set = sorted_set(values, stride, j);
    medians[j] = 0.5 * (set[3] + set[4]);
  }
}

void normalised_residuals_of_eight(const double* values, std::size_t stride, std::size_t count, const double* centres,
                                   double epsilon, double* residuals) {
  HWY_DYNAMIC_DISPATCH(NormalisedResidualsOfEight)(values, stride, count, centres, epsilon, residuals);
}
void scalar_normalised_residuals_of_eight(const double* values, std::size_t stride, std::size_t count,
                                          const double* centres, double epsilon, double* residuals) {
  for (std::size_t j = 0; j < count; ++j) {
    std::array<double, 8> set = sorted_set(values, stride, j);
    const double median = 0.5 * (set[3] + set[4]);
    for (double& value : set) value = std::abs(value - median);
    std::sort(set.begin(), set.end());
    residuals[j] = std::abs(centres[j] - median) / (0.5 * (set[3] + set[4]) + epsilon);
  }
}

}  // namespace bosfuse::fusion

#endif  // HWY_ONCE
