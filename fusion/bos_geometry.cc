#include "fusion/bos_geometry.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

bool positive(double value) { return std::isfinite(value) && value > 0; }

}  // namespace

double gladstone_dale_air_m3_per_kg(double wavelength_m) {
  const double ratio = 6.7132e-8 / wavelength_m;
  return 2.2244e-4 * (1 + ratio * ratio);
}

std::string BosGeometryOptions::Validate() const {
  if (!(wavelength_nm >= 200 && wavelength_nm <= 2000)) return "wavelength_nm must lie in 200..2000";
  if (!positive(ambient_pressure_pa)) return "ambient_pressure_pa must be positive";
  if (!(std::isfinite(ambient_temperature_c) && ambient_temperature_c > -kZeroCelsiusK)) {
    return "ambient_temperature_c must be above absolute zero";
  }
  if (!positive(z_d_m)) return "z_d_m (flow to background distance) must be positive";
  if (!positive(depth_m)) return "depth_m (depth of the flow along the line of sight) must be positive";
  if (!positive(magnification)) return "magnification must be positive";
  if (!positive(pixel_pitch_um)) return "pixel_pitch_um must be positive";
  if (!(std::isfinite(px_per_mm_flow) && px_per_mm_flow >= 0)) return "px_per_mm_flow must be positive (or 0: derived)";
  return {};
}

BosGeometry::BosGeometry(const BosGeometryOptions& options) : options_(options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  k_gd_ = gladstone_dale_air_m3_per_kg(options.wavelength_nm * 1e-9);
  n0_ = 1 + k_gd_ * ambient_density_kg_per_m3();
}

double BosGeometry::ambient_density_kg_per_m3() const {
  return options_.ambient_pressure_pa / (kSpecificGasConstantAir * ambient_temperature_k());
}

double BosGeometry::px_per_m_flow() const {
  if (options_.px_per_mm_flow > 0) return options_.px_per_mm_flow * 1e3;
  return options_.magnification / (options_.pixel_pitch_um * 1e-6);
}

double BosGeometry::refractive_index(double temperature_c) const {
  const double density = options_.ambient_pressure_pa / (kSpecificGasConstantAir * (temperature_c + kZeroCelsiusK));
  return 1 + k_gd_ * density;
}

double BosGeometry::temperature_c(double refractive_index) const {
  const double density = (refractive_index - 1) / k_gd_;
  if (!(density > 0)) return std::numeric_limits<double>::quiet_NaN();
  return options_.ambient_pressure_pa / (density * kSpecificGasConstantAir) - kZeroCelsiusK;
}

double BosGeometry::shift_px(double dn_per_m) const {
  const double deflection_rad = options_.depth_m / n0_ * dn_per_m;
  return -options_.magnification * options_.z_d_m * deflection_rad / (options_.pixel_pitch_um * 1e-6);
}

double BosGeometry::gradient_per_m(double shift_px) const { return shift_px / this->shift_px(1.0); }

double BosGeometry::celsius_per_px_shift_per_px_length() const {
  // Δn over one px of length for a 1 px shift, then dT/dn = −T/(n − 1) at ambient.
  const double dn_per_px_length = std::abs(gradient_per_m(1.0)) / px_per_m_flow();
  return dn_per_px_length * ambient_temperature_k() / (n0_ - 1);
}

std::string BosGeometry::brief_report() const {
  std::ostringstream out;
  out << std::setprecision(4);
  out << "Gladstone-Dale K = " << k_gd_ << " m^3/kg at " << options_.wavelength_nm << " nm; ambient "
      << options_.ambient_temperature_c << " degC, " << options_.ambient_pressure_pa
      << " Pa: rho0 = " << ambient_density_kg_per_m3() << " kg/m^3, n0 - 1 = " << n0_ - 1 << "\n";
  out << "Z_D = " << options_.z_d_m << " m, L = " << options_.depth_m << " m, M = " << options_.magnification
      << ", pixel pitch " << options_.pixel_pitch_um << " um, " << px_per_m_flow() * 1e-3
      << " px/mm at the flow plane\n";
  out << "1 px shift = gradient dn/dx of " << std::abs(gradient_per_m(1.0)) << " 1/m\n";
  const double sensitivity = celsius_per_px_shift_per_px_length();
  out << "sensitivity: " << sensitivity << " degC per px of shift per px of length (" << sensitivity * 100
      << " degC per px over 100 px)\n";
  return out.str();
}

}  // namespace bosfuse::fusion
