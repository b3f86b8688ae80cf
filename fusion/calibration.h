#pragma once
// Calibration of BOS against thermocouples: over a run, the thermocouple's
// temperature rise above the anchor (the ambient air the reference image
// shows; pipeline/calibrate.h), ΔT_tc, is
// fitted against the BOS quantity at the thermocouple's image position —
// the displacement magnitude there (giving the paper's "°C per pixel" for
// that position), or the physical model's ΔT (giving a scale on the model).
//
// The fit is weighted linear least squares, by default through the origin
// (no shift, no rise: ΔT = c·x), optionally with an intercept. The slope's
// standard uncertainty is scaled by the residual variance
// s² = Σw·r² / (n − p) (weights then only need to be relative, 1/σ²), the
// convention of the Newton fits. Points with a non-finite x, y or weight are
// dropped and counted; a fit that cannot be made says why and is not ok.
// r² is 1 − SSR/SST with SST about the mean of y (also through the origin:
// a line worse than a constant has r² < 0).
//
// A fit that can be made may still be no calibration: calibration_problems()
// checks it against physics and the data (CalibrationChecks), each problem
// named with its numbers. The sign physics expects: the reference image is
// taken without the flow, and air refracts less the hotter it is
// (Gladstone–Dale and the ideal gas: n − 1 = K·p/(R·T), dn/dT = −(n − 1)/T
// < 0). So where a heated flow is hotter than the reference's air, it bends
// rays more, and the shift magnitude grows with the temperature rise:
// °C per px of |shift| is positive (negative for a flow colder than the
// reference's air). The shift range the calibration spans at the
// thermocouple must exceed a multiple of the shift's uncertainty, or BOS
// sees no shift there (a thermocouple on a plume's centreline, where the
// gradient and so the deflection vanish by symmetry).

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace bosfuse::fusion {

struct CalibrationOptions {
  bool through_origin = true;
  std::size_t min_points = 3;

  std::string Validate() const;  // empty when valid
};

struct LinearCalibration {
  bool ok = false;
  std::string message;  // why not ok
  bool through_origin = true;
  double slope = 0;  // °C per unit of x (°C/px for the shift)
  double slope_std_error = 0;
  double intercept = 0;  // °C; 0 through the origin
  double intercept_std_error = 0;
  double residual_rms = 0;  // unweighted, °C
  double r2 = 0;            // 1 − SSR/SST about the mean of y; NaN when y does not vary
  std::size_t points = 0;
  std::size_t rejected_non_finite = 0;
  double x_min = 0, x_max = 0;  // the range the calibration is valid for

  double apply(double x) const { return intercept + slope * x; }
  std::string brief_report() const;
};

// `weights` empty: all 1. Throws std::invalid_argument when lengths differ
// or the options are invalid.
LinearCalibration fit_linear_calibration(std::span<const double> x, std::span<const double> y,
                                         std::span<const double> weights = {}, const CalibrationOptions& options = {});

// What a calibration must satisfy to be stored (pipeline/calibrate.h).
struct CalibrationChecks {
  std::size_t min_points = 5;
  double min_r2 = 0.9;
  double max_residual_rms_c = 1.0;
  double min_shift_range_sigmas = 3;   // x_max − x_min ≥ this × the shift's σ
  double shift_noise_floor_px = 0.05;  // the shift's σ when the probe has none
  int expected_sign = +1;              // +1: a heated flow; −1: one colder than the reference's air

  std::string Validate() const;  // empty when valid
};

// The shift's standard uncertainty the range check uses, and where it came from.
struct ShiftUncertainty {
  double sigma_px = 0;
  std::string source;  // "the probe's median sigma" or "the default noise floor ..."
};

// The median of the positive, finite σ of the probe's samples (0 means not
// estimated); none: the checks' noise floor.
ShiftUncertainty shift_uncertainty(std::span<const double> sigma_px, const CalibrationChecks& checks);

// Every check `fit` fails, each a sentence naming its numbers; empty: none.
// A fit that is not ok fails with its own message only.
std::vector<std::string> calibration_problems(const LinearCalibration& fit, const ShiftUncertainty& shift,
                                              const CalibrationChecks& checks);

}  // namespace bosfuse::fusion
