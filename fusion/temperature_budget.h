#pragma once
// The Type-B uncertainty budget of a BOS temperature: the systematic parts,
// those no repetition of frames averages away, each stated as a standard
// uncertainty and combined as the GUM does (JCGM 100:2008, §5.1: the root
// sum of squares of sensitivity × standard uncertainty, the inputs taken as
// uncorrelated). Use it beside the random uncertainty of a node (the
// weighted solve's) to say what a BOS temperature is worth as a measurement.
//
// The chain it differentiates (bos_geometry.h): the integrated index change
// δn scales as 1 / (Z_D · L · M^m) — m = 2 when the flow plane's scale is
// derived from the magnification, 1 when it is given — and
//     T = 1 / (1/T_amb + δn · R / (K · p)),
// so with a = 1/T − 1/T_amb (kelvin), which the node's T and T_amb give,
//     ∂T/∂T_amb = T² / T_amb²,
//     ∂T/∂ln K = ∂T/∂ln p = ∂T/∂ln Z_D = ∂T/∂ln L = T² · a,   ∂T/∂ln M = m · T² · a.
// Every part but the ambient temperature scales the excess T − T_amb, so it
// moves a cooling curve's T0 and T_amb but hardly its rate k.
//
// One more part compares a window's average with a thermocouple's point:
// for a smooth field the mean over a w × w window differs from its centre
// by (w² / 24) · ∇²T, which the temperature field's neighbours give at the
// node; its size is taken as a standard uncertainty (not a correction: the
// thermocouple's own position is not known better than a window).

#include <optional>
#include <string>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/temperature_field.h"

namespace bosfuse::fusion {

// Standard uncertainties (k = 1) of the set-up. The defaults are what a
// careful set-up without special metrology achieves (docs/UNCERTAINTY.md
// says why each); an experiment file states its own.
struct TypeBUncertainties {
  double gladstone_dale_relative = 0.001;  // dry-air formula for room air (humidity, CO2)
  double ambient_pressure_pa = 1000;       // no barometer: the weather's range about the standard
  double ambient_temperature_c = 0.5;      // the room's reading
  double z_d_relative = 0.01;              // flow to background, by tape: 5 mm in 0.5 m
  double magnification_relative = 0.01;    // from a scale in the image
  double depth_relative = 0.05;            // the flow's extent along the line of sight (2-D assumption)

  std::string Validate() const;  // empty when valid: each finite and ≥ 0
};

struct BudgetComponent {
  std::string quantity;           // "Z_D", "ambient temperature", ...
  std::string unit;               // of the standard uncertainty: "relative", "Pa", "°C"
  double standard_uncertainty = 0;
  double sensitivity = 0;         // °C per unit of the standard uncertainty
  double contribution_c = 0;      // |sensitivity| × standard uncertainty
};

struct TemperatureBudget {
  double temperature_c = 0;
  std::vector<BudgetComponent> components;
  double combined_c = 0;  // root sum of squares of the contributions

  // The budget as a Markdown table, one component a row, and the combined one.
  std::string table() const;
};

// The budget of a BOS temperature `temperature_c` measured with `geometry`;
// `window_average_c`, when known, is the window-against-point part (see
// window_average_uncertainty_c). Throws std::invalid_argument for invalid
// uncertainties or a temperature at or below absolute zero.
TemperatureBudget temperature_budget(const BosGeometry& geometry, const TypeBUncertainties& u, double temperature_c,
                                     std::optional<double> window_average_c = std::nullopt);

// (w² / 24) · |∇²T| at the node nearest (x_px, y_px), for a window of
// `window_px`; nullopt where that node or one of its four neighbours is not
// measured, not physical or off the grid.
std::optional<double> window_average_uncertainty_c(const TemperatureField& field, double x_px, double y_px,
                                                   double window_px);

}  // namespace bosfuse::fusion
