// The SIMD kernels' shared set-up: which target dispatch may pick (the
// BOSFUSE_SIMD cap, applied once before the first kernel call) and the name
// of the one it picked. The kernels themselves are one file per family:
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

#include "fusion/simd_dispatch.h"
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

#include <spdlog/spdlog.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <vector>

namespace bosfuse::fusion {

HWY_EXPORT(TargetName);

namespace {

std::once_flag environment_applied;

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

void apply_environment_once() { std::call_once(environment_applied, apply_simd_environment); }

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
