#pragma once
// Calibration of BOS against thermocouples: over a run, the thermocouple's
// temperature rise above its reading at the reference frame, ΔT_tc, is
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

#include <cstddef>
#include <span>
#include <string>

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

}  // namespace bosfuse::fusion
