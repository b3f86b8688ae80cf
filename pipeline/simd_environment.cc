#include "pipeline/simd_environment.h"

#include <spdlog/spdlog.h>

#include <cstdlib>

#include "fusion/simd_kernels.h"

namespace bosfuse::pipeline {

void apply_simd_environment() {
  const char* text = std::getenv("BOSFUSE_SIMD");
  const auto limit = fusion::parse_simd_limit(text ? text : "");
  if (!limit) spdlog::warn("BOSFUSE_SIMD='{}' is not auto, avx2, sse4 or portable; using auto", text);
  fusion::limit_simd_targets(limit.value_or(fusion::SimdLimit::kAuto));
}

}  // namespace bosfuse::pipeline
