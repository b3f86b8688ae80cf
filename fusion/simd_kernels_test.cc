#include "fusion/simd_kernels.h"

#include <gtest/gtest.h>
#include <hwy/highway.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

namespace bosfuse::fusion {
namespace {

// A centred reference window and a patch inside a wider buffer, so rows of
// the patch are not contiguous and its right edge is not the buffer's.
struct Inputs {
  int n, side;
  std::size_t stride;
  std::vector<float> reference, buffer;
  const float* patch() const { return buffer.data() + stride + 3; }
};

Inputs random_inputs(int n, int side, unsigned seed) {
  Inputs in{n, side, static_cast<std::size_t>(n + side - 1 + 7), {}, {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  in.reference.resize(static_cast<std::size_t>(n) * n);
  for (auto& a : in.reference) a = grey(rng) - 0.5f;
  in.buffer.resize(in.stride * (n + side + 1));
  for (auto& b : in.buffer) b = grey(rng);
  return in;
}

// Σ |a·b| for one shift: the scale float rounding is relative to (the
// products themselves may nearly cancel, the reference being centred).
double magnitude(const Inputs& in, int dx, int dy) {
  double sum = 0;
  for (int y = 0; y < in.n; ++y) {
    for (int x = 0; x < in.n; ++x) {
      sum += std::abs(double(in.reference[y * in.n + x]) * in.patch()[(y + dy) * in.stride + x + dx]);
    }
  }
  return sum;
}

void expect_kernel_matches_reference(int n, int side, unsigned seed) {
  SCOPED_TRACE(testing::Message() << "n=" << n << " side=" << side << " target=" << simd_target_name());
  const Inputs in = random_inputs(n, side, seed);
  const std::size_t count = static_cast<std::size_t>(side) * side;
  std::vector<double> simd(count, -1.0), reference(count, -2.0);
  accumulate_products(in.reference.data(), in.patch(), in.stride, n, side, simd.data());
  scalar_accumulate_products(in.reference.data(), in.patch(), in.stride, n, side, reference.data());
  for (int dy = 0; dy < side; ++dy) {
    for (int dx = 0; dx < side; ++dx) {
      const std::size_t i = static_cast<std::size_t>(dy) * side + dx;
      ASSERT_NEAR(simd[i], reference[i], 1e-6 * magnitude(in, dx, dy)) << "dx=" << dx << " dy=" << dy;
    }
  }
}

void expect_all_sizes_match() {
  unsigned seed = 1;
  for (const int n : {1, 3, 8, 13, 16, 24, 32, 64}) {
    for (const int side : {1, 3, 4, 5, 7, 9, 17}) expect_kernel_matches_reference(n, side, seed++);
  }
  expect_kernel_matches_reference(128, 5, seed++);
}

// Every test leaves the dispatch as it found it: no cap, no mock.
class SimdKernels : public testing::Test {
 protected:
  void TearDown() override {
    hwy::SetSupportedTargetsForTest(0);
    limit_simd_targets(SimdLimit::kAuto);
  }
};

TEST_F(SimdKernels, MatchTheScalarReference) { expect_all_sizes_match(); }

TEST_F(SimdKernels, MatchTheScalarReferenceOnEveryTargetOfThisCpu) {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  for (const std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_EQ(simd_target_name(), hwy::TargetName(target));
    expect_all_sizes_match();
  }
}

TEST_F(SimdKernels, TheEnvironmentForcesThePortableTarget) {
  ASSERT_EQ(setenv("BOSFUSE_SIMD", "portable", 1), 0);
  apply_simd_environment();
  const std::string name = simd_target_name();
  EXPECT_TRUE(name == "SCALAR" || name == "EMU128") << name;
  expect_all_sizes_match();
  ASSERT_EQ(unsetenv("BOSFUSE_SIMD"), 0);
  apply_simd_environment();
  EXPECT_EQ(simd_target_name(), hwy::TargetName(hwy::SupportedAndGeneratedTargets().front()));
}

TEST_F(SimdKernels, ALimitCapsTheTarget) {
  limit_simd_targets(SimdLimit::kSse4);
  const std::string name = simd_target_name();
  EXPECT_NE(name, "AVX2");
  EXPECT_NE(name, "AVX3");
  expect_all_sizes_match();
}

TEST(SimdLimit, ParsesTheEnvironmentValues) {
  EXPECT_EQ(parse_simd_limit(""), SimdLimit::kAuto);
  EXPECT_EQ(parse_simd_limit("auto"), SimdLimit::kAuto);
  EXPECT_EQ(parse_simd_limit("avx2"), SimdLimit::kAvx2);
  EXPECT_EQ(parse_simd_limit("sse4"), SimdLimit::kSse4);
  EXPECT_EQ(parse_simd_limit("portable"), SimdLimit::kPortable);
  EXPECT_EQ(parse_simd_limit("AVX2"), std::nullopt);
  EXPECT_EQ(parse_simd_limit("neon"), std::nullopt);
}

}  // namespace
}  // namespace bosfuse::fusion
