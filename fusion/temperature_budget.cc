#include "fusion/temperature_budget.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

bool usable(double value) { return std::isfinite(value) && value >= 0; }

BudgetComponent component(std::string quantity, std::string unit, double standard_uncertainty, double sensitivity) {
  return {std::move(quantity), std::move(unit), standard_uncertainty, sensitivity,
          std::abs(sensitivity) * standard_uncertainty};
}

}  // namespace

std::string TypeBUncertainties::Validate() const {
  for (const auto& [value, name] : {std::pair{gladstone_dale_relative, "gladstone_dale_relative"},
                                    {ambient_pressure_pa, "ambient_pressure_pa"},
                                    {ambient_temperature_c, "ambient_temperature_c"},
                                    {z_d_relative, "z_d_relative"},
                                    {magnification_relative, "magnification_relative"},
                                    {depth_relative, "depth_relative"}}) {
    if (!usable(value)) return fmt::format("the standard uncertainty {} must be finite and at least 0", name);
  }
  return {};
}

TemperatureBudget temperature_budget(const BosGeometry& geometry, const TypeBUncertainties& u, double temperature_c,
                                     std::optional<double> window_correction_sigma_c) {
  if (const auto problem = u.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  const double t_k = temperature_c + kZeroCelsiusK;
  if (!(t_k > 0)) throw std::invalid_argument(fmt::format("no budget for {} °C", temperature_c));
  const auto& o = geometry.options();
  const double ambient_k = geometry.ambient_temperature_k();
  // ∂T/∂ln x for every x that scales δn / (K p) (the header's a = 1/T − 1/T_amb).
  const double per_log = t_k * t_k * (1 / t_k - 1 / ambient_k);
  const double magnification_power = o.px_per_mm_flow > 0 ? 1 : 2;
  TemperatureBudget budget;
  budget.temperature_c = temperature_c;
  budget.components = {
      component("ambient temperature", "°C", u.ambient_temperature_c, t_k * t_k / (ambient_k * ambient_k)),
      component("ambient pressure", "Pa", u.ambient_pressure_pa, per_log / o.ambient_pressure_pa),
      component("Gladstone–Dale constant", "relative", u.gladstone_dale_relative, per_log),
      component("Z_D (flow to background)", "relative", u.z_d_relative, per_log),
      component("magnification", "relative", u.magnification_relative, magnification_power * per_log),
      component("depth L (line of sight)", "relative", u.depth_relative, per_log),
  };
  if (window_correction_sigma_c) {
    budget.components.push_back(
        component("window-average correction (curvature)", "°C", *window_correction_sigma_c, 1.0));
  }
  double sum_sq = 0;
  for (const auto& c : budget.components) sum_sq += c.contribution_c * c.contribution_c;
  budget.combined_c = std::sqrt(sum_sq);
  return budget;
}

std::string TemperatureBudget::table() const {
  std::string out = fmt::format("| quantity | standard uncertainty | sensitivity | contribution at {:.2f} °C |\n"
                                "|---|---|---|---|\n",
                                temperature_c);
  for (const auto& c : components) {
    out += fmt::format("| {} | {:.3g} {} | {:.3g} °C per {} | {:.3f} °C |\n", c.quantity, c.standard_uncertainty,
                       c.unit, c.sensitivity, c.unit == "relative" ? "unit" : c.unit, c.contribution_c);
  }
  out += fmt::format("| **combined (root sum of squares)** | | | **{:.3f} °C** |\n", combined_c);
  return out;
}

namespace {

// κ of the evaluator alone (the header's measurements).
CurvatureCoefficient evaluator_coefficient(const EvaluatorOptions& e) {
  if (e.method == Method::kOpticalFlow) {
    const double box = e.flow.window_px * e.flow.window_px / 24.0;
    return {box, box};
  }
  const double w = e.xcorr.window_px;
  if (e.xcorr.passes >= 2 && e.xcorr.deform) return {0.0, 1.5 * (w * w) / (16.0 * 16.0)};
  // A box, as measured within 2 %; σ 5 % for the pixel grid's (w² − 1)/24.
  return {w * w / 24.0, 0.05 * w * w / 24.0};
}

}  // namespace

double CurvatureCoefficient::effective_window_px() const { return kappa_px2 > 0 ? std::sqrt(24 * kappa_px2) : 0.0; }

CurvatureCoefficient chain_curvature_coefficient(const EvaluatorOptions& evaluator, double grid_step_px) {
  const CurvatureCoefficient e = evaluator_coefficient(evaluator);
  // The solve's h²/16 was measured to 1 %; its σ is the evaluator's.
  return {e.kappa_px2 + grid_step_px * grid_step_px / 16.0, e.sigma_px2};
}

std::optional<WindowCorrection> window_correction(const TemperatureField& field, double x_px, double y_px,
                                                  const CurvatureCoefficient& chain) {
  if (field.rows < 3 || field.cols < 3 || !(field.step_px > 0)) return std::nullopt;
  const double h = field.step_px;
  const double fx = (x_px - field.x0_px) / h, fy = (y_px - field.y0_px) / h;
  const long col = std::lround(fx), row = std::lround(fy);
  if (row < 1 || col < 1 || row > field.rows - 2 || col > field.cols - 2) return std::nullopt;
  // The bilinear interpolation's own term per axis at fraction a of the cell.
  const double ax = fx - std::floor(fx), ay = fy - std::floor(fy);
  const double kx = chain.kappa_px2 + ax * (1 - ax) * h * h / 2, ky = chain.kappa_px2 + ay * (1 - ay) * h * h / 2;
  WindowCorrection out;
  double laplacian = 0, correction = 0;
  // −(kx ∂²T/∂x² + ky ∂²T/∂y²), the second differences at the nearest node.
  for (const auto& [dr, dc] : {std::pair{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
    const std::size_t i = field.index(static_cast<int>(row) + dr, static_cast<int>(col) + dc);
    if (!field.measured[i] || !field.physical[i]) return std::nullopt;
    const double lap_weight = (dr == 0 && dc == 0 ? -4.0 : 1.0) / (h * h);
    const double weight = (dr == 0 && dc == 0 ? 2 * (kx + ky) : -(dr != 0 ? ky : kx)) / (h * h);
    laplacian += lap_weight * field.temperature_c[i];
    correction += weight * field.temperature_c[i];
    out.nodes.push_back(i);
    out.weights.push_back(weight);
  }
  out.correction_c = correction;
  out.laplacian_c_per_px2 = laplacian;
  out.coefficient_sigma_c = chain.sigma_px2 * std::abs(laplacian);
  return out;
}

double window_correction_sigma_c(const WindowCorrection& c, std::optional<double> noise_sigma_c) {
  if (!noise_sigma_c || !std::isfinite(*noise_sigma_c)) return std::hypot(c.coefficient_sigma_c, c.correction_c);
  return std::hypot(c.coefficient_sigma_c, *noise_sigma_c);
}

}  // namespace bosfuse::fusion
