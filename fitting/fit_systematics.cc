#include "fitting/fit_systematics.h"

#include <cmath>

namespace bosfuse::fitting {

FitSystematics propagate_systematics(std::span<const double> time_s, std::span<const double> temperature_c,
                                     std::span<const double> sigma_c, const NewtonFitOptions& options,
                                     const NewtonFit& fit, const std::vector<SystematicInput>& inputs) {
  FitSystematics out;
  if (!fit.ok()) {
    out.message = "the fit failed";
    return out;
  }
  double k2 = 0, t02 = 0, amb2 = 0;
  std::vector<double> shifted(temperature_c.size());
  for (const SystematicInput& input : inputs) {
    if (input.shift_c.size() != temperature_c.size()) {
      out.message = "the input '" + input.quantity + "' has no shift for every sample";
      return out;
    }
    for (std::size_t i = 0; i < shifted.size(); ++i) shifted[i] = temperature_c[i] + input.shift_c[i];
    const NewtonFit moved =
        sigma_c.empty() ? fit_newton(time_s, shifted, options) : fit_newton(time_s, shifted, sigma_c, options);
    if (!moved.ok()) {
      out.message = "the fit shifted by '" + input.quantity + "' failed: " + moved.summary.message;
      return out;
    }
    const ParameterShifts d{moved.k_per_s.value - fit.k_per_s.value, moved.t0_c.value - fit.t0_c.value,
                            moved.ambient_c.value - fit.ambient_c.value};
    out.effects.push_back({input.quantity, d});
    k2 += d.k_per_s * d.k_per_s;
    t02 += d.t0_c * d.t0_c;
    amb2 += d.t_amb_c * d.t_amb_c;
  }
  out.combined = {std::sqrt(k2), std::sqrt(t02), std::sqrt(amb2)};
  out.ok = true;
  return out;
}

}  // namespace bosfuse::fitting
