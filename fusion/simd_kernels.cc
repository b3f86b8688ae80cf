// Highway compiles this file once per target: foreach_target.h includes it
// again for each, with HWY_NAMESPACE naming the target; the code after
// HWY_ONCE is compiled only once and dispatches between them.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fusion/simd_kernels.cc"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
// Must follow foreach_target.h.
#include "hwy/highway.h"

#include "fusion/simd_kernels.h"

HWY_BEFORE_NAMESPACE();
namespace bosfuse::fusion {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Adds the lanes to `total` in double, lowest lane first: the order in
// which the scalar reference adds its columns.
template <class D>
HWY_INLINE double AddLanes(D d, hn::Vec<D> v, double total) {
  HWY_ALIGN float lanes[hn::MaxLanes(D())];
  hn::Store(v, d, lanes);
  for (std::size_t i = 0; i < hn::Lanes(d); ++i) total += lanes[i];
  return total;
}

// Four neighbouring shifts share each load of the reference, so a multiply-
// add costs 1.25 loads rather than 2 (loads, not arithmetic, bound this
// loop), and four independent sums hide the multiply-add's latency.
// Columns [i, n) in vectors of d, then the rest in halves of d down to one
// lane, so no load reaches past column n of the window.
template <class D>
HWY_INLINE void FourShifts(D d, const float* HWY_RESTRICT a, const float* HWY_RESTRICT b, std::size_t stride, int n,
                           int i, double* totals) {
  const int lanes = static_cast<int>(hn::Lanes(d));
  for (; i + lanes <= n; i += lanes) {
    auto s0 = hn::Zero(d), s1 = hn::Zero(d), s2 = hn::Zero(d), s3 = hn::Zero(d);
    for (int y = 0; y < n; ++y) {
      const auto va = hn::LoadU(d, a + static_cast<std::size_t>(y) * n + i);
      const float* row = b + y * stride + i;
      s0 = hn::MulAdd(va, hn::LoadU(d, row), s0);
      s1 = hn::MulAdd(va, hn::LoadU(d, row + 1), s1);
      s2 = hn::MulAdd(va, hn::LoadU(d, row + 2), s2);
      s3 = hn::MulAdd(va, hn::LoadU(d, row + 3), s3);
    }
    totals[0] = AddLanes(d, s0, totals[0]);
    totals[1] = AddLanes(d, s1, totals[1]);
    totals[2] = AddLanes(d, s2, totals[2]);
    totals[3] = AddLanes(d, s3, totals[3]);
  }
  if constexpr (hn::MaxLanes(D()) > 1) {
    if (i < n) FourShifts(hn::Half<D>(), a, b, stride, n, i, totals);
  }
}

// One shift: the last side % 4 of a row of shifts.
template <class D>
HWY_INLINE void OneShift(D d, const float* HWY_RESTRICT a, const float* HWY_RESTRICT b, std::size_t stride, int n,
                         int i, double& total) {
  const int lanes = static_cast<int>(hn::Lanes(d));
  for (; i + lanes <= n; i += lanes) {
    auto s = hn::Zero(d);
    for (int y = 0; y < n; ++y) {
      s = hn::MulAdd(hn::LoadU(d, a + static_cast<std::size_t>(y) * n + i), hn::LoadU(d, b + y * stride + i), s);
    }
    total = AddLanes(d, s, total);
  }
  if constexpr (hn::MaxLanes(D()) > 1) {
    if (i < n) OneShift(hn::Half<D>(), a, b, stride, n, i, total);
  }
}

void AccumulateProducts(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                        double* products) {
  const hn::ScalableTag<float> d;
  for (int dy = 0; dy < side; ++dy) {
    const float* rows = patch + dy * patch_stride;
    double* out = products + static_cast<std::size_t>(dy) * side;
    int dx = 0;
    for (; dx + 4 <= side; dx += 4) {
      double totals[4] = {0, 0, 0, 0};
      FourShifts(d, reference, rows + dx, patch_stride, n, 0, totals);
      for (int k = 0; k < 4; ++k) out[dx + k] = totals[k];
    }
    for (; dx < side; ++dx) {
      double total = 0;
      OneShift(d, reference, rows + dx, patch_stride, n, 0, total);
      out[dx] = total;
    }
  }
}

// The target this code was compiled for, as dispatch sees it.
const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace bosfuse::fusion
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <spdlog/spdlog.h>

#include <cstdlib>
#include <mutex>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(AccumulateProducts);
HWY_EXPORT(TargetName);

namespace {

std::once_flag environment_applied;

void apply_environment_once() { std::call_once(environment_applied, apply_simd_environment); }

// The targets a limit rules out. Targets the CPU lacks are ruled out anyway.
std::int64_t disabled_targets(SimdLimit limit) {
  switch (limit) {
    case SimdLimit::kAuto:
      return 0;
    case SimdLimit::kAvx2:
      return HWY_AVX3 | HWY_AVX3_DL;
    case SimdLimit::kSse4:
      return HWY_AVX2 | HWY_AVX3 | HWY_AVX3_DL;
    case SimdLimit::kPortable:
      return ~(HWY_SCALAR | HWY_EMU128);
  }
  return 0;
}

}  // namespace

void accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                         double* products) {
  apply_environment_once();
  HWY_DYNAMIC_DISPATCH(AccumulateProducts)(reference, patch, patch_stride, n, side, products);
}

void scalar_accumulate_products(const float* reference, const float* patch, std::size_t patch_stride, int n, int side,
                                double* products) {
  std::vector<float> column(static_cast<std::size_t>(n));
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      for (int i = 0; i < n; ++i) column[i] = 0.f;
      for (int y = 0; y < n; ++y) {
        const float* a = reference + static_cast<std::size_t>(y) * n;
        const float* b = patch + (y + dy) * patch_stride + dx;
        for (int i = 0; i < n; ++i) column[i] += a[i] * b[i];
      }
      double total = 0;
      for (int i = 0; i < n; ++i) total += column[i];
      products[static_cast<std::size_t>(dy) * side + dx] = total;
    }
  }
}

std::optional<SimdLimit> parse_simd_limit(std::string_view text) {
  if (text.empty() || text == "auto") return SimdLimit::kAuto;
  if (text == "avx2") return SimdLimit::kAvx2;
  if (text == "sse4") return SimdLimit::kSse4;
  if (text == "portable") return SimdLimit::kPortable;
  return std::nullopt;
}

void limit_simd_targets(SimdLimit limit) {
  // Afterwards, so that a later first kernel call does not undo this limit.
  apply_environment_once();
  // DisableTargets also makes the next dispatch choose again.
  hwy::DisableTargets(disabled_targets(limit));
}

void apply_simd_environment() {
  const char* text = std::getenv("BOSFUSE_SIMD");
  const auto limit = parse_simd_limit(text ? text : "");
  // A typo must not stop a run that would give the same results anyway.
  if (!limit) spdlog::warn("BOSFUSE_SIMD='{}' is not auto, avx2, sse4 or portable; using auto", text);
  hwy::DisableTargets(disabled_targets(limit.value_or(SimdLimit::kAuto)));
}

std::string simd_target_name() {
  apply_environment_once();
  return HWY_DYNAMIC_DISPATCH(TargetName)();
}

}  // namespace bosfuse::fusion

#endif  // HWY_ONCE
