// The SIMD kernels' shared set-up: which target dispatch may pick (the cap
// limit_simd_targets sets) and the name of the one it picked. The kernels themselves are one file per family:
// simd_correlation.cc, simd_medians.cc, simd_resampling.cc.
// Highway compiles this file once per target: foreach_target.h includes it
// again for each, with HWY_NAMESPACE naming the target; the code after
// HWY_ONCE is compiled only once and dispatches between them.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fusion/simd_kernels.cc"
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

// The target this code was compiled for, as dispatch sees it.
const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace bosfuse::fusion
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(TargetName);

namespace {

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

std::optional<SimdLimit> parse_simd_limit(std::string_view text) {
  if (text.empty() || text == "auto") return SimdLimit::kAuto;
  if (text == "avx2") return SimdLimit::kAvx2;
  if (text == "sse4") return SimdLimit::kSse4;
  if (text == "portable") return SimdLimit::kPortable;
  return std::nullopt;
}

void limit_simd_targets(SimdLimit limit) {
  // DisableTargets also makes the next dispatch choose again.
  hwy::DisableTargets(disabled_targets(limit));
}

std::string simd_target_name() {
  return HWY_DYNAMIC_DISPATCH(TargetName)();
}

}  // namespace bosfuse::fusion

#endif  // HWY_ONCE
