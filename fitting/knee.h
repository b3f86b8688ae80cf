#pragma once
// The knee of a heated-then-cooled curve: the moment a heater was switched
// off, read from a thermocouple that warmed while it was on and cools once
// it is off. Use it to propose a forgotten "heater off" marker after the run
// (`bosfuse mark RUN "heater off" --estimate`), for the user to accept.
//
// Model: a hinge, continuous at the knee t_k, with its own slope and
// curvature on either side,
//   T(t) = a + b₁·(t − t_k) + c₁·(t − t_k)²   for t < t_k,
//   T(t) = a + b₂·(t − t_k) + c₂·(t − t_k)²   for t ≥ t_k,
// fitted by least squares (linear for a given t_k) to the samples around the
// curve's maximum, scanning t_k over the sample times and refining the best
// by a parabola through the residual sums. The window reaches as far after
// the maximum as the curve takes to fall by a fifth of its drop (and as far
// before it, where the record allows), short enough for the quadratics to
// follow an exponential. The standard uncertainty of t_k is where the
// residual sum's profile rises by s² (s² = SSR/(n − 6)), the profile
// likelihood's 1σ for Gaussian noise, combined with the quantisation of a
// kink between two samples (Δt/√12), which that profile understates.
//
// A thermocouple reads the curve through its own lag τ: its knee is rounded
// and comes up to about τ after the switch-off, a bias this estimate does not
// remove (docs/CONFIG.md, `time_constant_s`). A curve that falls (or rises)
// from its first sample to its last has no knee: the heater went off before
// the record started or after it ended.

#include <optional>
#include <span>
#include <string>

namespace bosfuse::fitting {

struct Knee {
  double t_s = 0;        // the knee, on the samples' time axis
  double sigma_t_s = 0;  // its standard uncertainty (1σ)
  double slope_before_per_s = 0;  // b₁, °C/s: > 0 while heating
  double slope_after_per_s = 0;   // b₂, °C/s: < 0 while cooling
  std::size_t points = 0;         // samples in the window fitted
};

struct KneeResult {
  std::optional<Knee> knee;
  std::string reason;  // why there is none
};

// `t_s` ascending, `temperature_c` of the same length; NaNs are skipped.
KneeResult find_knee(std::span<const double> t_s, std::span<const double> temperature_c);

}  // namespace bosfuse::fitting
