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
// One more part compares a window's average with a thermocouple's point,
// and is a known bias, so it is corrected (GUM §3.2.4) and only the
// correction's uncertainty enters the budget. For a smooth field every
// linear smoothing of the chain reads T + κ·∇²T at a node, κ its second
// moment over 2 (w²/24 for a w × w box: w_eff = sqrt(24 κ) is the box with
// the same deficit). The chain's κ at a node (chain_curvature_coefficient), measured
// on generated fields with known curvature (sim/window_response.h for the
// evaluator; fusion/temperature_budget_test.cc WindowCorrection.* for the
// whole chain; run `build/fusion/fusion_test --gtest_filter='WindowCorrection.*'`
// and `build/sim/sim_test --gtest_filter='WindowResponse.*'`), is the sum of
//   - the evaluator's: deformed multi-pass cross-correlation (passes ≥ 2,
//     deform) iterates its windows to the local shift and barely averages:
//     κ = 0 ± 1.5 px² for a 16 px final window, scaled as w² for others
//     (measured: −0.56 ± 0.37 px² over sinusoids of λ 96, 128, 192 px,
//     fitted as g = g0 − κk² so that a shift-scale error g0 ≠ 1 is not read
//     as curvature; +1.1 ± 1.2 and +1.8 ± 2.0 px² on Gaussian plumes of
//     radius 32, 42 px, peak shift 0.3 px, six seeds each; 32 px: −9.9 ±
//     0.7 px² on λ 192, 256, 384, inside 2 σ of 0 ± 6); without
//     deformation or with one pass the window is a box, κ = w²/24 (measured
//     w_eff 16.1 px for 16, 31.3 px for 32); optical flow, not measured, is
//     taken as its window's box with κ's σ equal to κ;
//   - the Poisson solve's: κ = h²/16 for grid step h (measured 3.96 px² for
//     h = 8, 0.99 for h = 4: its trapezoid gradient targets);
// so for the default chain (16 px, step 8) w_eff = 9.8 ± 1.8 px at a node,
// 0.61 of the window, where the uncorrected term took the box's 16 px
// (the whole chain measured on the plume: 11.0 px; without deformation
// 21.3 px against 18.8 stated). A probe between nodes reads the bilinear
// interpolation, which adds its own exact term per axis,
// a(1 − a)·h²/2 · ∂²T/∂x² at fraction a of the cell. The correction
// −(κ∇²T + interpolation) is a fixed linear
// combination of five nodes, so its noise is propagated exactly through the
// solve (TemperatureFieldSolver::average_sigma_c); its uncertainty is that
// noise and κ's σ times |∇²T|, combined.

#include <optional>
#include <string>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
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
// `window_correction_sigma_c`, when known, is the standard uncertainty of
// the window-average correction applied to it (WindowCorrection). Throws
// std::invalid_argument for invalid uncertainties or a temperature at or
// below absolute zero.
TemperatureBudget temperature_budget(const BosGeometry& geometry, const TypeBUncertainties& u, double temperature_c,
                                     std::optional<double> window_correction_sigma_c = std::nullopt);

// The chain's smoothing coefficient κ at a node (T read as T + κ·∇²T), in
// px², with its standard uncertainty; see the header's paragraph.
struct CurvatureCoefficient {
  double kappa_px2 = 0;
  double sigma_px2 = 0;
  double effective_window_px() const;  // sqrt(24 κ), 0 for κ ≤ 0
};
CurvatureCoefficient chain_curvature_coefficient(const EvaluatorOptions& evaluator, double grid_step_px);

// The correction of a probe's temperature for the chain's averaging, as the
// weights of the nodes it combines, so its noise can be propagated.
struct WindowCorrection {
  double correction_c = 0;     // add to the interpolated temperature
  double laplacian_c_per_px2 = 0;
  double coefficient_sigma_c = 0;  // κ's σ × |∇²T|
  std::vector<std::size_t> nodes;  // the nearest node and its four neighbours
  std::vector<double> weights;     // correction_c = Σ weights · T(nodes)
};

// The correction at (x_px, y_px) of a field read by bilinear interpolation;
// nullopt where the nearest node or one of its four neighbours is not
// measured, not physical or off the grid.
std::optional<WindowCorrection> window_correction(const TemperatureField& field, double x_px, double y_px,
                                                  const CurvatureCoefficient& chain);

// The correction's standard uncertainty: its coefficient's part and the
// noise of its five nodes (σ of Σ weights·T, from the solve), combined;
// without the noise's σ, the whole correction is taken as its uncertainty.
double window_correction_sigma_c(const WindowCorrection& c, std::optional<double> noise_sigma_c);

}  // namespace bosfuse::fusion
