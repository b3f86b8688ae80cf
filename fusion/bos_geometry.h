#pragma once
// BosGeometry is the optical set-up of a BOS experiment and the physics that
// links a background displacement to the air's refractive index and
// temperature. Use it to convert a displacement (px) into a refractive-index
// gradient (1/m) and back, and to state the set-up's sensitivity.
//
// Gas: Gladstone–Dale, n − 1 = K·ρ, with K from the wavelength by the
// dispersion formula K(λ) = 2.2244e-4 · (1 + (6.7132e-8 m / λ)²) m³/kg
// (Merzkirch, "Flow Visualization", 2nd ed., 1987, for air); the ideal gas
// ρ = p / (R·T), R = 287.05 J/(kg K). Temperatures are °C in this API and
// kelvin inside.
//
// Optics (small angles, a 2-D flow of depth L along the line of sight z):
// a ray traced from the camera through the flow turns towards higher n by
//     ε_x = (L / n0) · ∂n/∂x   (likewise ε_y),
// so the camera pixel that saw background point X now sees X + Z_D·ε. The
// background feature that was at X therefore appears displaced by −Z_D·ε at
// the background, i.e. on the sensor, in DESIGN.md's convention (a feature
// at (x, y) in the reference appears at (x + u, y + v) in the measurement):
//     u_px = −M · Z_D · ε_x / pixel_pitch,   v_px = −M · Z_D · ε_y / pixel_pitch,
// with M the magnification of the background on the sensor. Consequence: a
// hot spot (low n at its centre, a diverging lens) pulls the background
// towards its centre — displacements point inwards; a cold spot pushes
// them outwards. Image x and y are taken to run with the scene's x and y as
// the camera shows it (the image inversion of the lens is undone by the
// camera's readout, as always).
//
// Spatial derivatives need the scale at the flow plane, px_per_mm_flow; when
// it is not given it is taken as M / pixel_pitch, the background's scale,
// which is right when Z_D is small against the camera–flow distance.

#include <string>

namespace bosfuse::fusion {

inline constexpr double kSpecificGasConstantAir = 287.05;  // J/(kg K)
inline constexpr double kZeroCelsiusK = 273.15;

// Gladstone–Dale constant of air, m³/kg, for a vacuum wavelength in metres.
double gladstone_dale_air_m3_per_kg(double wavelength_m);

struct BosGeometryOptions {
  double wavelength_nm = 550;           // illumination (vacuum) wavelength
  double ambient_pressure_pa = 101325;  // taken as uniform over the field
  double ambient_temperature_c = 20;    // the undisturbed air: the Poisson boundary
  double z_d_m = 0.5;                   // flow (mid-depth) to background distance
  double depth_m = 0.1;                 // L: extent of the disturbance along the line of sight
  double magnification = 0.15;          // of the background on the sensor (image size / object size)
  double pixel_pitch_um = 5.0;          // sensor pixel pitch (of the image as evaluated, after any binning)
  double px_per_mm_flow = 0;            // image scale at the flow plane; 0: magnification / pixel pitch

  std::string Validate() const;  // empty when valid, else the first problem
};

class BosGeometry {
 public:
  // Throws std::invalid_argument with Validate()'s message.
  explicit BosGeometry(const BosGeometryOptions& options);

  const BosGeometryOptions& options() const { return options_; }
  double gladstone_dale_m3_per_kg() const { return k_gd_; }
  double ambient_temperature_k() const { return options_.ambient_temperature_c + kZeroCelsiusK; }
  double ambient_density_kg_per_m3() const;
  double ambient_refractive_index() const { return n0_; }
  double px_per_m_flow() const;

  double refractive_index(double temperature_c) const;
  // NaN when n ≤ 1 (no gas can have it): the caller flags it.
  double temperature_c(double refractive_index) const;

  // Displacement on the sensor (px) produced by a refractive-index gradient
  // (1/m) along the same axis, and the inverse.
  double shift_px(double dn_per_m) const;
  double gradient_per_m(double shift_px) const;

  // Linear sensitivity around ambient: the temperature change accumulated
  // when a 1 px displacement is integrated over 1 px of image length
  // (°C per px of shift per px of length). Multiply by a length in px (the
  // width of a plume, say) to get the paper's "°C per pixel" for that width.
  double celsius_per_px_shift_per_px_length() const;

  // A few lines a person can read: K, n0, ρ0, the scales and sensitivity.
  std::string brief_report() const;

 private:
  BosGeometryOptions options_;
  double k_gd_ = 0;
  double n0_ = 1;
};

}  // namespace bosfuse::fusion
