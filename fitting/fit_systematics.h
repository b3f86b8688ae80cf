#pragma once
// The systematic (Type-B) uncertainty of a cooling-curve fit's parameters:
// each input of a budget that no number of samples averages away (a BOS
// set-up's depth, magnification, ambient, ...; a calibration's slope) moves
// every sample of a series together, so it does not enter the fit's
// weights — it moves the whole curve. Use propagate_systematics() after
// fit_newton() on a series whose samples each carry the shift one standard
// uncertainty of every such input causes there (temperature_budget.h's
// sensitivity × standard uncertainty): the series is refitted shifted by
// each input, and the change of k, T0 and T_amb is that input's effect;
// the effects of independent inputs combine as root sum of squares (GUM,
// JCGM 100:2008 §5.1). A refit, not a derivative, so it holds for the fit
// exactly as it is (weights, ambient model, loss). Inputs that scale the
// excess over ambient move T0 and hardly k; the ambient's moves T0 and
// T_amb equally.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "fitting/newton_fit.h"

namespace bosfuse::fitting {

// One budget input: the shift of each sample (°C, in the series' order)
// by one standard uncertainty of it, fully correlated along the series.
struct SystematicInput {
  std::string quantity;
  std::vector<double> shift_c;
};

// Signed change of the parameters (k in 1/s, T0 and T_amb in °C).
struct ParameterShifts {
  double k_per_s = 0;
  double t0_c = 0;
  double t_amb_c = 0;
};

struct SystematicEffect {
  std::string quantity;
  ParameterShifts shift;
};

struct FitSystematics {
  bool ok = false;
  std::string message;                   // why not, when !ok
  std::vector<SystematicEffect> effects;  // one per input
  ParameterShifts combined;               // standard uncertainties: root sum of squares of the effects (≥ 0)
};

// `fit` is fit_newton(time_s, temperature_c, sigma_c, options) (sigma_c
// empty: unweighted); each input's shift_c has a value per sample. Not ok
// when the fit failed, an input's size differs or a refit fails.
FitSystematics propagate_systematics(std::span<const double> time_s, std::span<const double> temperature_c,
                                     std::span<const double> sigma_c, const NewtonFitOptions& options,
                                     const NewtonFit& fit, const std::vector<SystematicInput>& inputs);

}  // namespace bosfuse::fitting
