#pragma once
// The environment variable BOSFUSE_SIMD, which caps the targets fusion's
// SIMD kernels may use (fusion/simd_kernels.h: auto, avx2, sse4, portable;
// docs/CONFIG.md). fusion/ reads no environment, so the program applies it
// once at its start (app/main.cc), before any kernel runs; a test that
// changes the variable applies it again.

namespace bosfuse::pipeline {

// Reads BOSFUSE_SIMD and caps the kernels' targets by it (unset or empty:
// auto). An unknown value is warned about on the log and taken as auto: a
// typo must not stop a run that would give the same results anyway.
void apply_simd_environment();

}  // namespace bosfuse::pipeline
