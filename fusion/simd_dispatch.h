#pragma once
// The kernels' shared dispatch set-up, internal to the simd_*.cc files: the
// target cap (BOSFUSE_SIMD, simd_kernels.h) is applied once per process,
// before the first kernel call of any kernel family dispatches. Every
// public kernel wrapper calls this first; nothing outside fusion/simd_*.cc
// needs it.

namespace bosfuse::fusion {

// Applies BOSFUSE_SIMD the first time it is called; later calls do nothing.
void apply_environment_once();

}  // namespace bosfuse::fusion
