#pragma once
// ConvectionScene is the paper's experiment in numbers, the ground truth the
// simulator serves: a horizontal heated cylinder switched off at t = 0 and
// cooling by natural convection, the 2-D laminar plume rising above it, the
// thermocouples reading that plume, and the background displacement a camera
// sees through it. Use it to make simulated runs whose every number is known.
//
// Physics, in SI units and kelvin inside:
// - Cylinder: lumped capacitance, C'·dT/dt = −h·π·D·(T − T_amb) per unit
//   length, with h from the Churchill–Chu correlation for a horizontal
//   cylinder (air properties at the film temperature), so the decay slows as
//   the cylinder cools and departs from a pure exponential; or, as an option,
//   a constant h (a pure exponential, k = h·π·D / C').
// - Plume: a laminar plane plume from the line source Q' = h·π·D·(T − T_amb),
//   with the similarity scaling of a laminar line plume measured from a
//   virtual origin z_v below the cylinder's centre:
//     ΔT_c(z) = C_T · (Q'/ρc_p) · F^(−1/5) · ν^(−2/5) · (z − z_v)^(−3/5),
//     δ(z)    = C_δ · ν^(3/5) · F^(−1/5) · (z − z_v)^(2/5),   F = gβQ'/(ρc_p),
//   and a Gaussian profile across: ΔT = ΔT_c·exp(−(x/δ)²), capped at the
//   cylinder's own excess temperature, zero below the cylinder's top and,
//   with plume_onset_m > 0, rising from it smoothly over that height (a
//   smoothstep whose slope is in the gradient). With the default step the
//   plume's foot beside the holder's mask is a temperature jump that no
//   displacement shows, so the displacement is not quite the gradient of
//   the scene's temperature: integrated noise-free and window-corrected,
//   the demo's probes give k −0.19 % / −0.16 % from the point's with the
//   step and −0.09 % / −0.08 % with a 6 mm onset (sim/demo_chain_bias_test.cc).
//   C_T and C_δ are of the order laminar-plume solutions give and make the
//   magnitudes plausible; the exponents are the physics the tests check.
// - Thermocouples: the plume temperature at their position through a
//   first-order lag (time constant τ_s), plus Gaussian noise.
// - BOS: Gladstone–Dale n − 1 = K·ρ, ideal gas ρ = p/(R·T); a ray crossing
//   the plume along the cylinder's axis over the depth L is deflected by
//   ε = (L/n0)·∇n (the 2-D plume is uniform along the ray, so integrating
//   along it is exact), towards higher n, and hits the background Z_D
//   further on shifted by Z_D·ε. The camera, focused on the background,
//   therefore sees a background feature moved by −Z_D·ε: in image pixels
//   (x right, y down, z up) u = −Z_D·ε_x·s and v = +Z_D·ε_z·s, where s is
//   pixels per metre at the background. The gradient is analytic, computed
//   independently of fusion/'s inverse.
//
// Image geometry: the cylinder's centre at (cylinder_x_px, cylinder_y_px),
// px_per_mm at the background (the paper: 30 px/mm, magnification 0.15);
// the flow plane is taken at the same scale (the flow is close to the
// background compared with the camera distance).

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "sim/background_pattern.h"

namespace bosfuse::sim {

struct SceneOptions {
  // Cylinder and air.
  double diameter_m = 0.02;
  double heat_capacity_per_length_j_mk = 75;  // a thin-walled heater tube: τ ≈ 2 min
  double initial_c = 120;
  double ambient_c = 22;
  double pressure_pa = 101325;
  bool pure_exponential = false;  // constant h (evaluated at t = 0) instead of Churchill–Chu
  double duration_s = 600;        // the cooling is tabulated over [0, duration]
  // Plume.
  double virtual_origin_m = -0.02;           // z_v, relative to the cylinder's centre (below it)
  double plume_temperature_constant = 0.35;  // C_T
  double plume_width_constant = 3.5;         // C_δ
  double plume_onset_m = 0;                 // the plume's smooth rise above the cylinder's top; 0: a step (the demo's)
  // Optics and camera.
  double gladstone_dale_m3_kg = 2.26e-4;
  double depth_m = 0.1;  // L: the plume's extent along the line of sight (the cylinder's length)
  double z_d_m = 0.1;    // flow to background
  double px_per_mm = 30;
  int width_px = 640;
  int height_px = 480;
  double cylinder_x_px = 320;
  double cylinder_y_px = 400;

  std::string Validate() const;
};

struct SceneThermocouple {
  std::string name;
  double x_m = 0;  // from the cylinder's centre, right
  double z_m = 0;  // up
  double lag_s = 1.0;
  double noise_c = 0.05;
};

struct CameraModel {
  double noise_std = 0.01;  // fraction of full scale
  double blur_sigma_px = 0.5;
  int bit_depth = 8;
  double contrast = 1.0;   // < 1 imitates a poor sensor (a low quality index)
  double luminance = 0.0;  // added offset, fraction of full scale
  std::uint64_t seed = 11;
};

class ConvectionScene {
 public:
  explicit ConvectionScene(SceneOptions options);  // throws std::invalid_argument

  const SceneOptions& options() const { return options_; }

  // Cylinder (t in s after switch-off, ≥ 0).
  double cylinder_temperature_c(double t_s) const;
  double heat_transfer_coefficient_w_m2k(double cylinder_c) const;  // Churchill–Chu
  // The cooling rate the exponential option uses, and the initial one of Churchill–Chu.
  double initial_cooling_rate_per_s() const;

  // Plume.
  double centreline_excess_c(double z_m, double t_s) const;
  double plume_width_m(double z_m, double t_s) const;  // δ
  double temperature_c(double x_m, double z_m, double t_s) const;
  double refractive_index(double x_m, double z_m, double t_s) const;
  cv::Point2d refractive_gradient_per_m(double x_m, double z_m, double t_s) const;  // (∂n/∂x, ∂n/∂z), analytic

  // Image.
  cv::Point2d flow_position_m(double x_px, double y_px) const;  // (x, z)
  cv::Point2d image_position_px(double x_m, double z_m) const;
  cv::Point2d displacement_px(double x_px, double y_px, double t_s) const;  // (u, v), DESIGN.md convention
  // The temperature's mean over a square window of `window_px` centred at
  // (x, y) in the image: the budget's window-average term, below a point
  // sensor's reading where the profile is curved (by about (w²/24)·|∇²T| on
  // the plume's centreline). A BOS probe from deformed multi-pass windows
  // averages over less than this box (issue 29: about 0.6 of its deficit).
  double window_mean_temperature_c(double x_px, double y_px, double window_px, double t_s) const;
  cv::Mat holder_mask() const;  // CV_8U, 255 where the cylinder and its holder hide the background
  // The camera's frame at t; `with_flow` false gives the no-flow reference.
  cv::Mat render_frame(const BackgroundPattern& pattern, const CameraModel& camera, double t_s, bool with_flow,
                       std::uint64_t frame_index) const;

  // A thermocouple's reading at each of `times_s` (ascending, ≥ 0): lagged, then noisy.
  std::vector<double> thermocouple_readings(const SceneThermocouple& tc, const std::vector<double>& times_s,
                                            std::uint64_t seed) const;

 private:
  struct Onset {
    double value, slope_per_m;
  };
  Onset plume_onset(double z_m) const;  // the factor on the centreline excess and its ∂/∂z
  double excess_c(double t_s) const;  // cylinder − ambient
  double line_heat_w_m(double t_s) const;

  SceneOptions options_;
  std::vector<double> excess_table_c_;  // cylinder − ambient every kTableStepS
};

}  // namespace bosfuse::sim
