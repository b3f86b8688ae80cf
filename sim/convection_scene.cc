#include "sim/convection_scene.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "sim/cooling_signal.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::sim {
namespace {

constexpr double kKelvin = 273.15;
constexpr double kGasConstant = 287.05;  // J/(kg K), dry air
constexpr double kGravity = 9.81;
constexpr double kCpAir = 1005;  // J/(kg K)
constexpr double kTableStepS = 0.05;

// Dry air near atmospheric pressure (Sutherland's laws): good to a few % over 250-600 K.
struct Air {
  double density, viscosity_kinematic, diffusivity, expansion;
};

Air air_at(double t_k, double pressure_pa) {
  const double density = pressure_pa / (kGasConstant * t_k);
  const double mu = 1.716e-5 * std::pow(t_k / kKelvin, 1.5) * (kKelvin + 110.4) / (t_k + 110.4);
  const double conductivity = 0.0241 * std::pow(t_k / kKelvin, 1.5) * (kKelvin + 194.0) / (t_k + 194.0);
  return {density, mu / density, conductivity / (density * kCpAir), 1.0 / t_k};
}

double conductivity_at(double t_k) { return 0.0241 * std::pow(t_k / kKelvin, 1.5) * (kKelvin + 194.0) / (t_k + 194.0); }

// FNV-1a: a name's noise stream, the same on every platform.
std::uint64_t stream_of(const std::string& name) {
  std::uint64_t hash = 1469598103934665603ull;
  for (unsigned char c : name) hash = (hash ^ c) * 1099511628211ull;
  return hash;
}

}  // namespace

std::string SceneOptions::Validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(diameter_m) || !positive(heat_capacity_per_length_j_mk))
    return "cylinder size and heat capacity must be positive";
  if (!(initial_c > ambient_c)) return "the cylinder must start hotter than the ambient air";
  if (!positive(ambient_c + kKelvin) || !positive(pressure_pa))
    return "ambient temperature and pressure must be physical";
  if (!positive(duration_s) || duration_s > 1e5) return "duration must be positive (and at most 1e5 s)";
  if (!(virtual_origin_m < diameter_m / 2)) return "the plume's virtual origin must lie below the cylinder's top";
  if (!(plume_onset_m >= 0) || !std::isfinite(plume_onset_m)) return "the plume's onset must be 0 or positive";
  if (!positive(plume_temperature_constant) || !positive(plume_width_constant))
    return "plume constants must be positive";
  if (!positive(gladstone_dale_m3_kg) || !positive(depth_m) || !(z_d_m >= 0) || !positive(px_per_mm)) {
    return "optical constants and geometry must be positive";
  }
  if (width_px < 16 || height_px < 16) return "image must be at least 16 x 16 px";
  return {};
}

ConvectionScene::ConvectionScene(SceneOptions options) : options_(std::move(options)) {
  if (const std::string problem = options_.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  // RK4 on C' dΔT/dt = -h(T) π D ΔT; h frozen at t = 0 for the pure exponential.
  const double h0 = heat_transfer_coefficient_w_m2k(options_.initial_c);
  const auto rate = [&](double excess) {
    const double h = options_.pure_exponential ? h0 : heat_transfer_coefficient_w_m2k(options_.ambient_c + excess);
    return -h * M_PI * options_.diameter_m * excess / options_.heat_capacity_per_length_j_mk;
  };
  const auto steps = static_cast<std::size_t>(std::ceil(options_.duration_s / kTableStepS)) + 1;
  excess_table_c_.reserve(steps + 1);
  double excess = options_.initial_c - options_.ambient_c;
  excess_table_c_.push_back(excess);
  for (std::size_t i = 0; i < steps; ++i) {
    const double k1 = rate(excess), k2 = rate(excess + 0.5 * kTableStepS * k1);
    const double k3 = rate(excess + 0.5 * kTableStepS * k2), k4 = rate(excess + kTableStepS * k3);
    excess += kTableStepS / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    excess_table_c_.push_back(excess);
  }
}

double ConvectionScene::heat_transfer_coefficient_w_m2k(double cylinder_c) const {
  const double surface_k = cylinder_c + kKelvin, ambient_k = options_.ambient_c + kKelvin;
  const double film_k = 0.5 * (surface_k + ambient_k);
  const Air air = air_at(film_k, options_.pressure_pa);
  const double d = options_.diameter_m;
  const double rayleigh = kGravity * air.expansion * std::abs(surface_k - ambient_k) * d * d * d /
                          (air.viscosity_kinematic * air.diffusivity);
  const double prandtl = air.viscosity_kinematic / air.diffusivity;
  const double root =
      0.60 + 0.387 * std::pow(rayleigh, 1.0 / 6) / std::pow(1 + std::pow(0.559 / prandtl, 9.0 / 16), 8.0 / 27);
  return root * root * conductivity_at(film_k) / d;
}

double ConvectionScene::initial_cooling_rate_per_s() const {
  return heat_transfer_coefficient_w_m2k(options_.initial_c) * M_PI * options_.diameter_m /
         options_.heat_capacity_per_length_j_mk;
}

double ConvectionScene::excess_c(double t_s) const {
  if (!(t_s >= 0) || t_s > options_.duration_s) {
    throw std::out_of_range("scene time " + std::to_string(t_s) + " s outside [0, duration]");
  }
  const double position = t_s / kTableStepS;
  const auto i = std::min(static_cast<std::size_t>(position), excess_table_c_.size() - 2);
  const double f = position - static_cast<double>(i);
  return excess_table_c_[i] + f * (excess_table_c_[i + 1] - excess_table_c_[i]);
}

double ConvectionScene::cylinder_temperature_c(double t_s) const { return options_.ambient_c + excess_c(t_s); }

// What the cylinder loses is what the plume carries: the same h as the cooling.
double ConvectionScene::line_heat_w_m(double t_s) const {
  const double excess = excess_c(t_s);
  const double h = heat_transfer_coefficient_w_m2k(options_.pure_exponential ? options_.initial_c
                                                                             : options_.ambient_c + excess);
  return h * M_PI * options_.diameter_m * excess;
}

double ConvectionScene::centreline_excess_c(double z_m, double t_s) const {
  if (z_m < options_.diameter_m / 2) return 0;  // below the cylinder's top: no plume
  const Air air = air_at(options_.ambient_c + kKelvin, options_.pressure_pa);
  const double source = line_heat_w_m(t_s) / (air.density * kCpAir);  // K m²/s
  const double buoyancy = kGravity * air.expansion * source;          // F, m³/s³
  const double height = z_m - options_.virtual_origin_m;
  const double excess = options_.plume_temperature_constant * source * std::pow(buoyancy, -0.2) *
                        std::pow(air.viscosity_kinematic, -0.4) * std::pow(height, -0.6);
  return plume_onset(z_m).value * std::min(excess, excess_c(t_s));
}

// 0 at the cylinder's top, 1 from plume_onset_m above it, smoothstep between.
ConvectionScene::Onset ConvectionScene::plume_onset(double z_m) const {
  const double w = options_.plume_onset_m;
  if (!(w > 0)) return {z_m >= options_.diameter_m / 2 ? 1.0 : 0.0, 0.0};
  const double x = std::clamp((z_m - options_.diameter_m / 2) / w, 0.0, 1.0);
  return {x * x * (3 - 2 * x), 6 * x * (1 - x) / w};
}

double ConvectionScene::plume_width_m(double z_m, double t_s) const {
  const Air air = air_at(options_.ambient_c + kKelvin, options_.pressure_pa);
  const double buoyancy = kGravity * air.expansion * line_heat_w_m(t_s) / (air.density * kCpAir);
  const double height = std::max(z_m - options_.virtual_origin_m, 1e-6);
  return options_.plume_width_constant * std::pow(air.viscosity_kinematic, 0.6) * std::pow(buoyancy, -0.2) *
         std::pow(height, 0.4);
}

double ConvectionScene::temperature_c(double x_m, double z_m, double t_s) const {
  const double centre = centreline_excess_c(z_m, t_s);
  if (centre == 0) return options_.ambient_c;
  const double r = x_m / plume_width_m(z_m, t_s);
  return options_.ambient_c + centre * std::exp(-r * r);
}

double ConvectionScene::refractive_index(double x_m, double z_m, double t_s) const {
  const double density = options_.pressure_pa / (kGasConstant * (temperature_c(x_m, z_m, t_s) + kKelvin));
  return 1 + options_.gladstone_dale_m3_kg * density;
}

// n = 1 + K p / (R T): ∇n = −K p / (R T²) ∇T, with ∇T of the Gaussian
// profile under the similarity laws (ΔT_c ∝ h^−3/5, δ ∝ h^2/5, h = z − z_v).
cv::Point2d ConvectionScene::refractive_gradient_per_m(double x_m, double z_m, double t_s) const {
  const double centre = centreline_excess_c(z_m, t_s);
  const Onset onset = plume_onset(z_m);
  if (centre == 0 || centre >= onset.value * excess_c(t_s)) return {0, 0};  // no plume, or capped (uniform) there
  const double delta = plume_width_m(z_m, t_s);
  const double height = z_m - options_.virtual_origin_m;
  const double profile = std::exp(-(x_m / delta) * (x_m / delta));
  const double dt_dx = centre * profile * (-2 * x_m / (delta * delta));
  const double dcentre_dz = -0.6 * centre / height + centre * onset.slope_per_m / onset.value;
  const double ddelta_dz = 0.4 * delta / height;
  const double dt_dz = dcentre_dz * profile + centre * profile * (2 * x_m * x_m / (delta * delta * delta)) * ddelta_dz;
  const double t_k = options_.ambient_c + centre * profile + kKelvin;
  const double dn_dt = -options_.gladstone_dale_m3_kg * options_.pressure_pa / (kGasConstant * t_k * t_k);
  return {dn_dt * dt_dx, dn_dt * dt_dz};
}

cv::Point2d ConvectionScene::flow_position_m(double x_px, double y_px) const {
  const double m_per_px = 1e-3 / options_.px_per_mm;
  return {(x_px - options_.cylinder_x_px) * m_per_px, (options_.cylinder_y_px - y_px) * m_per_px};
}

cv::Point2d ConvectionScene::image_position_px(double x_m, double z_m) const {
  const double px_per_m = options_.px_per_mm * 1e3;
  return {options_.cylinder_x_px + x_m * px_per_m, options_.cylinder_y_px - z_m * px_per_m};
}

cv::Point2d ConvectionScene::displacement_px(double x_px, double y_px, double t_s) const {
  const cv::Point2d at = flow_position_m(x_px, y_px);
  const cv::Point2d gradient = refractive_gradient_per_m(at.x, at.y, t_s);
  const double n0 = refractive_index(1e3, -1e3, t_s);  // ambient air, far from the plume
  const double scale = options_.z_d_m * options_.depth_m / n0 * options_.px_per_mm * 1e3;  // ε → px
  return {-scale * gradient.x, scale * gradient.y};
}

double ConvectionScene::window_mean_temperature_c(double x_px, double y_px, double window_px, double t_s) const {
  constexpr int kSteps = 32;  // midpoint rule: 1e-4 relative on the demo's plume
  double sum = 0;
  for (int i = 0; i < kSteps; ++i) {
    for (int j = 0; j < kSteps; ++j) {
      const cv::Point2d at =
          flow_position_m(x_px + window_px * ((i + 0.5) / kSteps - 0.5), y_px + window_px * ((j + 0.5) / kSteps - 0.5));
      sum += temperature_c(at.x, at.y, t_s);
    }
  }
  return sum / (kSteps * kSteps);
}

cv::Mat ConvectionScene::holder_mask() const {
  cv::Mat mask(options_.height_px, options_.width_px, CV_8U, cv::Scalar(0));
  const double radius_px = options_.diameter_m / 2 * options_.px_per_mm * 1e3;
  const cv::Point centre(static_cast<int>(std::lround(options_.cylinder_x_px)),
                         static_cast<int>(std::lround(options_.cylinder_y_px)));
  cv::circle(mask, centre, static_cast<int>(std::ceil(radius_px * 1.15)), cv::Scalar(255), cv::FILLED);
  const int half_width = static_cast<int>(std::ceil(radius_px * 0.4));
  cv::rectangle(mask, cv::Point(centre.x - half_width, centre.y), cv::Point(centre.x + half_width, mask.rows - 1),
                cv::Scalar(255), cv::FILLED);
  return mask;
}

cv::Mat ConvectionScene::render_frame(const BackgroundPattern& pattern, const CameraModel& camera, double t_s,
                                      bool with_flow, std::uint64_t frame_index) const {
  if (pattern.size != cv::Size(options_.width_px, options_.height_px)) {
    throw std::invalid_argument("background pattern size differs from the scene's image size");
  }
  DisplacementFunction flow;
  if (with_flow) flow = [this, t_s](double x, double y) { return displacement_px(x, y, t_s); };
  cv::Mat image = render_dots(pattern, flow);
  image.setTo(cv::Scalar(0.05), holder_mask());  // the dark cylinder and holder hide the background
  image = image * camera.contrast + camera.luminance;
  return camera_image(image, camera.blur_sigma_px, camera.noise_std, camera.bit_depth, camera.seed, frame_index);
}

std::vector<double> ConvectionScene::thermocouple_readings(const SceneThermocouple& tc,
                                                           const std::vector<double>& times_s,
                                                           std::uint64_t seed) const {
  // τ dT_s/dt = T − T_s, stepped exactly for piecewise-linear T; before t = 0
  // the heater ran long enough for the sensor to be in equilibrium.
  std::vector<double> readings;
  readings.reserve(times_s.size());
  double sensor_c = temperature_c(tc.x_m, tc.z_m, 0);
  double now_s = 0;
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    const double target_s = times_s[i];
    if (target_s < now_s) throw std::invalid_argument("thermocouple times must ascend");
    while (now_s < target_s) {
      const double step = std::min(kTableStepS, target_s - now_s);
      const double decay = tc.lag_s > 0 ? std::exp(-step / tc.lag_s) : 0.0;
      sensor_c = temperature_c(tc.x_m, tc.z_m, now_s + step) +
                 (sensor_c - temperature_c(tc.x_m, tc.z_m, now_s + step)) * decay;
      now_s += step;
    }
    readings.push_back(sensor_c + tc.noise_c * hashed_normal(seed, stream_of(tc.name), i));
  }
  return readings;
}

}  // namespace bosfuse::sim
