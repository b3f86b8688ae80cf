#pragma once
// BOSFUSE_AVX2_CLONES builds a hot loop for AVX2 beside the baseline, the
// loader picking what the CPU has (GCC's target_clones, resolved by an
// ifunc at load time). Under ThreadSanitizer the ifunc's resolver runs
// before the sanitizer's runtime exists and crashes the program as it loads,
// so there the loop is built for the baseline only.

#if defined(__SANITIZE_THREAD__)
#define BOSFUSE_AVX2_CLONES
#else
#define BOSFUSE_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#endif
