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
                                     std::optional<double> window_average_c) {
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
  if (window_average_c) budget.components.push_back(component("window average against a point", "°C",
                                                              *window_average_c, 1.0));
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

std::optional<double> window_average_uncertainty_c(const TemperatureField& field, double x_px, double y_px,
                                                   double window_px) {
  if (field.rows < 3 || field.cols < 3 || !(field.step_px > 0) || !(window_px > 0)) return std::nullopt;
  const long col = std::lround((x_px - field.x0_px) / field.step_px);
  const long row = std::lround((y_px - field.y0_px) / field.step_px);
  if (row < 1 || col < 1 || row > field.rows - 2 || col > field.cols - 2) return std::nullopt;
  double neighbours = 0;
  for (const auto& [dr, dc] : {std::pair{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
    const std::size_t i = field.index(static_cast<int>(row) + dr, static_cast<int>(col) + dc);
    if (!field.measured[i] || !field.physical[i]) return std::nullopt;
    neighbours += (dr == 0 && dc == 0 ? -4.0 : 1.0) * field.temperature_c[i];
  }
  const double laplacian_per_px2 = neighbours / (field.step_px * field.step_px);
  return window_px * window_px / 24.0 * std::abs(laplacian_per_px2);
}

}  // namespace bosfuse::fusion
