#include "fitting/knee.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace bosfuse::fitting {
namespace {

// Heated for `off_s` (rising towards 80 °C), then Newton cooling: the
// simulator's curve (sim/cooling_signal.h), built here so fitting/ stays
// free of the simulator.
struct HeatedCurve {
  std::vector<double> t, y;
};

HeatedCurve heated_curve(double off_s, double k, double noise_c, unsigned seed, double period_s = 1, int n = 400) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0, noise_c);
  HeatedCurve c;
  for (int i = 0; i < n; ++i) {
    const double t = i * period_s;
    const double mean = t < off_s ? 22 + 58 * std::expm1(-k * t) / std::expm1(-k * off_s)
                                  : 22 + 58 * std::exp(-k * (t - off_s));
    c.t.push_back(t);
    c.y.push_back(mean + noise(random));
  }
  return c;
}

TEST(Knee, FindsTheSwitchOffWithinItsUncertainty) {
  int inside_2_sigma = 0;
  constexpr int kSeeds = 20;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    const double off_s = 100 + 3.3 * seed;  // between the samples, not on them
    const HeatedCurve c = heated_curve(off_s, 0.01, 0.05, seed);
    const KneeResult r = find_knee(c.t, c.y);
    ASSERT_TRUE(r.knee) << r.reason;
    EXPECT_NEAR(r.knee->t_s, off_s, 0.5) << seed;
    EXPECT_LT(std::abs(r.knee->t_s - off_s), 4 * r.knee->sigma_t_s) << seed << ": σ " << r.knee->sigma_t_s;
    EXPECT_GT(r.knee->slope_before_per_s, 0);
    EXPECT_LT(r.knee->slope_after_per_s, 0);
    inside_2_sigma += std::abs(r.knee->t_s - off_s) < 2 * r.knee->sigma_t_s;
  }
  EXPECT_GE(inside_2_sigma, kSeeds * 3 / 4) << "σ is too small";
}

// docs/CONFIG.md's figure: a sensor with a first-order lag τ shows the knee
// late, by less than τ (0.7–0.95 τ at τ = 1 s and 3 s, sampled each second).
TEST(Knee, ALaggingSensorsKneeIsLateByLessThanItsTimeConstant) {
  for (const double tau_s : {1.0, 3.0}) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const double off_s = 100 + 3.3 * seed;
      const HeatedCurve fine = heated_curve(off_s, 0.01, 0, seed, 0.1, 4000);
      std::mt19937 random(seed);
      std::normal_distribution<double> noise(0, 0.05);
      std::vector<double> t, y;
      double lagged = fine.y.front();
      for (std::size_t i = 0; i < fine.t.size(); ++i) {
        lagged += (fine.y[i] - lagged) * -std::expm1(-0.1 / tau_s);
        if (i % 10 == 0) {
          t.push_back(fine.t[i]);
          y.push_back(lagged + noise(random));
        }
      }
      const KneeResult r = find_knee(t, y);
      ASSERT_TRUE(r.knee) << r.reason;
      EXPECT_GT(r.knee->t_s - off_s, 0.5 * tau_s) << "τ " << tau_s << " seed " << seed;
      EXPECT_LT(r.knee->t_s - off_s, tau_s) << "τ " << tau_s << " seed " << seed;
    }
  }
}

TEST(Knee, ACurveWithoutATurnHasNone) {
  const HeatedCurve cooling = heated_curve(0, 0.01, 0.05, 3);
  EXPECT_FALSE(find_knee(cooling.t, cooling.y).knee);
  EXPECT_EQ(find_knee(cooling.t, cooling.y).reason, "the curve falls from its first sample: the heater was off before");
  const HeatedCurve heating = heated_curve(1000, 0.01, 0.05, 3);
  EXPECT_FALSE(find_knee(heating.t, heating.y).knee) << "still heating at the end";
  const std::vector<double> few{0, 1, 2};
  EXPECT_FALSE(find_knee(few, few).knee);
}

TEST(Knee, NanSamplesAreSkipped) {
  HeatedCurve c = heated_curve(150, 0.01, 0.05, 5);
  for (std::size_t i = 0; i < c.y.size(); i += 17) c.y[i] = std::nan("");
  const KneeResult r = find_knee(c.t, c.y);
  ASSERT_TRUE(r.knee) << r.reason;
  EXPECT_NEAR(r.knee->t_s, 150, 0.5);
}

}  // namespace
}  // namespace bosfuse::fitting
