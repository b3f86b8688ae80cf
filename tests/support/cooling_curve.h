#pragma once
// Synthetic Newton cooling records for fitting tests and benchmarks: a known
// curve sampled at a fixed interval with seeded Gaussian noise, so every
// test knows the true parameters it should recover.

#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

namespace bosfuse::testing {

struct CoolingCurve {
  double ambient_c = 22.0;
  double t0_c = 80.0;
  double k_per_s = 0.01;
  double at(double t_s) const { return ambient_c + (t0_c - ambient_c) * std::exp(-k_per_s * t_s); }
};

struct CoolingRecord {
  std::vector<double> time_s;
  std::vector<double> temperature_c;
};

// n samples every dt_s, the first at start_s (the curve's t = 0), with
// Gaussian noise of sigma_c drawn from `seed`.
inline CoolingRecord sample_cooling(const CoolingCurve& curve, std::size_t n, double dt_s, double sigma_c,
                                    unsigned seed, double start_s = 0.0) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, sigma_c > 0 ? sigma_c : 1.0);
  CoolingRecord r;
  r.time_s.reserve(n);
  r.temperature_c.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * dt_s;
    r.time_s.push_back(start_s + t);
    r.temperature_c.push_back(curve.at(t) + (sigma_c > 0 ? noise(random) : 0.0));
  }
  return r;
}

}  // namespace bosfuse::testing
