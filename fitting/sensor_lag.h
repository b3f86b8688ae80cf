#pragma once
// A sensor's first-order response lag, the thermocouple's in particular: it
// reads T_s with τ·dT_s/dt = T − T_s, i.e. the true temperature convolved
// with exp(−t/τ)/τ. Use it before comparing a lagged sensor with one that
// has no lag (the BOS probe sees the air at the frame's instant), so that
// the lag is not reported as disagreement.
//
// On a Newton cooling curve T = T_amb + ΔT·e^(−kt) a lagged sensor, once its
// start-up transient e^(−t/τ) has died out, reads
//     T_s = T_amb + ΔT/(1 − kτ) · e^(−kt):
// the same k and the same T_amb, but an amplitude larger by 1/(1 − kτ) (it
// still reads warmer than the air that has already cooled). Its paired
// difference from a sensor without lag is τ·|dT/dt| = kτ·(T − T_amb).
// The inverse, T = T_s + τ·dT_s/dt, is what delagged() applies, with dT_s/dt
// from the sensor's own fitted curve (a derivative of noisy samples would
// amplify their noise): T0 − T_amb scales by (1 − kτ), k and T_amb stay.
//
// τ is a property of the sensor (its bead, sheath and the air speed): stated
// per channel in the experiment file (time_constant_s) or, when not stated,
// estimated by estimate_lag() from the paired differences. On an exponential
// a lag and a gain error of the other sensor look alike (both are
// proportional to T − T_amb), so an estimated τ also absorbs any amplitude
// difference: it is reported as such, not as a measured time constant.

#include <cstddef>
#include <optional>

#include "fitting/newton_fit.h"
#include "fitting/series.h"

namespace bosfuse::fitting {

// The curve the lagged sensor followed: T0 − T_amb multiplied by (1 − kτ),
// its covariance carried through that map (τ is taken as exact). A failed
// fit, or τ = 0, comes back as it was. Throws std::invalid_argument for a
// negative or non-finite τ.
NewtonFit delagged(const NewtonFit& lagged, double time_constant_s);

// The readings de-lagged: each T_s + τ·dT/dt with dT/dt from `fit` (the
// series' own fit), the slope −k·(T_fit(t) − T_amb). Returned unchanged for
// τ = 0 or a failed fit.
CleanSeries delagged(const CleanSeries& lagged, const NewtonFit& fit, double time_constant_s);

struct LagEstimate {
  double time_constant_s = 0.0;  // may come out ≤ 0: then the sensor does not lag the reference
  double std_error_s = 0.0;
  std::size_t points = 0;  // reference times the regression used
};

// τ by least squares on the paired differences at the reference's times,
//     T_s(t_i) − T_ref(t_i) = b − τ·dT_s/dt(t_i),
// with T_s interpolated linearly and dT_s/dt from the lagged sensor's fit;
// the intercept b keeps a constant calibration offset out of τ. nullopt
// when the fit failed, fewer than 4 times overlap, or the rate does not vary
// (nothing to tell τ from b). Both series on one time base (their origins).
std::optional<LagEstimate> estimate_lag(const CleanSeries& lagged, const NewtonFit& lagged_fit,
                                        const CleanSeries& reference);

}  // namespace bosfuse::fitting
