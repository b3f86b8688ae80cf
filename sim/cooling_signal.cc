#include "sim/cooling_signal.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace bosfuse::sim {
namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// A double in (0, 1), never 0 so the logarithm below is finite.
double unit_open(std::uint64_t bits) { return (static_cast<double>(bits >> 11) + 0.5) * 0x1.0p-53; }

}  // namespace

double hashed_normal(std::uint64_t seed, std::uint64_t stream, std::uint64_t draw) {
  const std::uint64_t base = splitmix64(splitmix64(seed ^ splitmix64(stream)) ^ draw);
  const double u1 = unit_open(base);
  const double u2 = unit_open(splitmix64(base));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

std::string CoolingSignal::Validate() const {
  if (!std::isfinite(ambient_c) || !std::isfinite(initial_c)) return "temperatures must be finite";
  if (!(k_per_s >= 0) || !std::isfinite(k_per_s)) return "cooling rate k must be finite and not negative";
  if (!(noise_c >= 0) || !std::isfinite(noise_c)) return "noise must be finite and not negative";
  if (!(heated_s >= 0) || !std::isfinite(heated_s)) return "the heating time must be finite and not negative";
  return {};
}

double CoolingSignal::mean_c(double t_s) const {
  if (t_s < heated_s) {
    // Heating towards initial_c, reached at the switch-off; linear when k = 0.
    const double reached = k_per_s > 0 ? -std::expm1(-k_per_s * t_s) / -std::expm1(-k_per_s * heated_s)
                                       : t_s / heated_s;
    return ambient_c + (initial_c - ambient_c) * std::max(reached, 0.0);
  }
  return ambient_c + (initial_c - ambient_c) * std::exp(-k_per_s * (t_s - heated_s));
}

double CoolingSignal::sample_c(double t_s, int channel, std::uint64_t draw) const {
  return mean_c(t_s) + noise_c * hashed_normal(seed, static_cast<std::uint64_t>(channel), draw);
}

}  // namespace bosfuse::sim
