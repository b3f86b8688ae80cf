// Configure-time probe (cmake/Sanitizers.cmake): prints the Highway targets
// an instrumented build need not compile on this machine, i.e. all that
// fusion/simd_*.cc would compile except the best one this CPU runs and
// the portable baseline (SCALAR/EMU128, which BOSFUSE_SIMD=portable selects).
#include <cstdint>
#include <cstdio>

#include "hwy/targets.h"

int main() {
  const std::int64_t runnable = hwy::SupportedTargets() & HWY_TARGETS;
  const std::int64_t best = runnable & -runnable;  // lower bit = better target
  const std::int64_t keep = best | HWY_SCALAR | HWY_EMU128;
  std::printf("%lld", static_cast<long long>(HWY_TARGETS & ~keep));
  return 0;
}
