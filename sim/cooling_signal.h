#pragma once
// CoolingSignal is the temperature a simulated thermocouple reads: Newton's
// law of cooling, T(t) = T_amb + (T0 − T_amb)·exp(−k·t), plus Gaussian noise.
// With heated_s > 0 the heater is on for that long first: the reading rises
// from T_amb to T0 as T_amb + (T0 − T_amb)·(1 − exp(−k·t)) / (1 − exp(−k·H)),
// and cools from the switch-off at t = H, a knee whose time is known (for
// `bosfuse mark --estimate`).
// The noise is a pure function of (seed, channel, draw), so a simulated run
// is reproducible and a test can recompute exactly what was served.

#include <cstdint>
#include <string>

namespace bosfuse::sim {

struct CoolingSignal {
  double ambient_c = 22.0;
  double initial_c = 80.0;
  double k_per_s = 0.01;
  double noise_c = 0.05;  // standard deviation
  std::uint64_t seed = 1;
  // H: the heater is switched off this long after the start. Last, as
  // brace initialisers elsewhere list the seed fifth.
  double heated_s = 0;

  std::string Validate() const;  // empty when valid
  double mean_c(double t_s) const;
  double sample_c(double t_s, int channel, std::uint64_t draw) const;
};

// A standard normal deviate that depends only on its arguments.
double hashed_normal(std::uint64_t seed, std::uint64_t stream, std::uint64_t draw);

}  // namespace bosfuse::sim
