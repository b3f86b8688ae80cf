// The simulated experiment checked against its own physics: the cooling law
// it claims, the plume's similarity scaling measured from its temperature
// field, the BOS forward model against finite differences of n, the sensor
// lag, and rendered frames that an evaluator reads back.

#include "sim/convection_scene.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fusion/displacement_evaluator.h"
#include "sim/demo_setup.h"

namespace bosfuse::sim {
namespace {

// Least-squares slope of log(y) against log(x).
double log_log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

TEST(ConvectionScene, PureExponentialOptionIsNewtonsLaw) {
  SceneOptions options;
  options.pure_exponential = true;
  const ConvectionScene scene(options);
  const double k = scene.initial_cooling_rate_per_s();
  EXPECT_GT(k, 1.0 / 600);  // a cooling time of minutes, as the demo needs
  EXPECT_LT(k, 1.0 / 30);
  for (double t : {0.0, 30.0, 100.0, 250.0}) {
    const double expected = options.ambient_c + (options.initial_c - options.ambient_c) * std::exp(-k * t);
    EXPECT_NEAR(scene.cylinder_temperature_c(t), expected, 1e-6 * options.initial_c) << "t = " << t;
  }
}

TEST(ConvectionScene, ChurchillChuCoolingSlowsAsTheCylinderCools) {
  const ConvectionScene scene(SceneOptions{});
  const double h_hot = scene.heat_transfer_coefficient_w_m2k(120);
  EXPECT_GT(h_hot, 5);  // free convection from a 20 mm cylinder in air: several W/m²K
  EXPECT_LT(h_hot, 15);
  EXPECT_LT(scene.heat_transfer_coefficient_w_m2k(40), h_hot);
  // Local rate −d ln ΔT/dt: starts at the initial rate and falls with ΔT.
  const auto rate_at = [&](double t) {
    const double a = scene.cylinder_temperature_c(t - 0.5) - 22, b = scene.cylinder_temperature_c(t + 0.5) - 22;
    return std::log(a / b);
  };
  EXPECT_NEAR(rate_at(0.5), scene.initial_cooling_rate_per_s(), 0.01 * scene.initial_cooling_rate_per_s());
  EXPECT_LT(rate_at(300), 0.95 * rate_at(1));
  EXPECT_THROW(scene.cylinder_temperature_c(601), std::out_of_range);
}

// Measured from the temperature field itself: the maximum across the plume
// and the half-width where the excess falls to 1/e of it.
TEST(ConvectionScene, PlumeFollowsLaminarLinePlumeScaling) {
  const ConvectionScene scene(SceneOptions{});
  const double t = 30, ambient = scene.options().ambient_c, z_v = scene.options().virtual_origin_m;
  std::vector<double> heights, peaks, widths;
  for (double z = 0.03; z <= 0.15; z += 0.01) {
    double peak = 0;
    for (int i = -200; i <= 200; ++i) peak = std::max(peak, scene.temperature_c(i * 1e-5, z, t) - ambient);
    double half = 0;  // bisection for the 1/e point on the right
    double lo = 0, hi = 0.1;
    for (int i = 0; i < 60; ++i) {
      half = 0.5 * (lo + hi);
      (scene.temperature_c(half, z, t) - ambient > peak / std::exp(1.0) ? lo : hi) = half;
    }
    heights.push_back(z - z_v);
    peaks.push_back(peak);
    widths.push_back(half);
  }
  EXPECT_NEAR(log_log_slope(heights, peaks), -0.6, 0.01);
  EXPECT_NEAR(log_log_slope(heights, widths), 0.4, 0.01);
  // Weaker source later: the plume cools with the cylinder.
  EXPECT_LT(scene.centreline_excess_c(0.055, 200), scene.centreline_excess_c(0.055, 10));
}

TEST(ConvectionScene, ForwardDisplacementMatchesFiniteDifferencesOfN) {
  const ConvectionScene scene(SceneOptions{});
  const auto& o = scene.options();
  const double n0 = scene.refractive_index(1, -1, 0);
  const double to_px = o.z_d_m * o.depth_m / n0 * o.px_per_mm * 1e3;
  const double h = 1e-6;
  int checked = 0;
  for (double x = -0.006; x <= 0.006; x += 0.0015) {
    for (double z = 0.02; z <= 0.08; z += 0.015) {
      const double t = 20;
      const double dn_dx = (scene.refractive_index(x + h, z, t) - scene.refractive_index(x - h, z, t)) / (2 * h);
      const double dn_dz = (scene.refractive_index(x, z + h, t) - scene.refractive_index(x, z - h, t)) / (2 * h);
      const cv::Point2d pixel = scene.image_position_px(x, z);
      const cv::Point2d d = scene.displacement_px(pixel.x, pixel.y, t);
      EXPECT_NEAR(d.x, -to_px * dn_dx, 1e-4 * std::abs(to_px * dn_dx) + 1e-6) << x << ", " << z;
      EXPECT_NEAR(d.y, to_px * dn_dz, 1e-4 * std::abs(to_px * dn_dz) + 1e-6) << x << ", " << z;
      ++checked;
    }
  }
  EXPECT_GT(checked, 30);
  // Light bends towards the cooler, denser air beside the plume, so the
  // background right of the centreline appears moved left (towards the plume).
  const cv::Point2d right = scene.image_position_px(0.003, 0.05);
  EXPECT_LT(scene.displacement_px(right.x, right.y, 10).x, 0);
}

TEST(ConvectionScene, ThermocouplesLagTheAirTheySit) {
  const ConvectionScene scene(SceneOptions{});
  const SceneThermocouple tc{"tc", 0.0, 0.055, 5.0, 0.0};
  std::vector<double> times;
  for (double t = 0; t <= 120; t += 1) times.push_back(t);
  const auto readings = scene.thermocouple_readings(tc, times, 3);
  EXPECT_NEAR(readings[0], scene.temperature_c(0, 0.055, 0), 1e-9);
  for (std::size_t i = 30; i < times.size(); i += 30) {
    const double now = scene.temperature_c(0, 0.055, times[i]);
    const double lagged = scene.temperature_c(0, 0.055, times[i] - tc.lag_s);
    EXPECT_GT(readings[i], now);  // cooling: the sensor is behind
    EXPECT_LT(std::abs(readings[i] - lagged), 0.2 * std::abs(readings[i] - now) + 1e-3);
  }
  const SceneThermocouple noisy{"tc", 0.0, 0.055, 5.0, 0.1};
  EXPECT_EQ(scene.thermocouple_readings(noisy, times, 3), scene.thermocouple_readings(noisy, times, 3));
}

// Render a reference and a frame through the plume and read the displacement
// back with the cross-correlation evaluator at a thermocouple's position.
// On the plume's centreline the profile is curved, so a window's mean lies
// below the point by the budget's window-average term (w²/24)·|∇²T|, to
// leading order in w/δ; a vanishing window is the point.
TEST(ConvectionScene, AWindowsMeanOnTheCentrelineIsThePointLessTheCurvatureTerm) {
  const DemoSetup demo = demo_setup(DemoOptions{}.experiment_s);
  const SceneOptions& o = demo.scene;
  const ConvectionScene& scene = *demo.model;
  const cv::Point2d at = scene.image_position_px(0, 0.035);
  const double t_s = 5;
  const double h_px = 0.5, h_m = h_px * 1e-3 / o.px_per_mm;
  const auto t = [&](double dx_px, double dy_px) {
    const cv::Point2d m = scene.flow_position_m(at.x + dx_px, at.y + dy_px);
    return scene.temperature_c(m.x, m.y, t_s);
  };
  const double laplacian_per_m2 = (t(h_px, 0) + t(-h_px, 0) + t(0, h_px) + t(0, -h_px) - 4 * t(0, 0)) / (h_m * h_m);
  const double w_px = 16, w_m = w_px * 1e-3 / o.px_per_mm;
  const double expected_c = w_m * w_m / 24 * laplacian_per_m2;  // negative: a peak
  const double deficit_c = scene.window_mean_temperature_c(at.x, at.y, w_px, t_s) - t(0, 0);
  EXPECT_LT(expected_c, -0.2) << "the demo's plume is curved enough to matter";
  EXPECT_NEAR(deficit_c, expected_c, 0.1 * std::abs(expected_c));
  EXPECT_NEAR(scene.window_mean_temperature_c(at.x, at.y, 0.01, t_s), t(0, 0), 1e-6);
}

TEST(ConvectionScene, RenderedFramesCarryTheForwardDisplacement) {
  SceneOptions options;
  options.width_px = 320;
  options.height_px = 240;
  options.cylinder_x_px = 160;
  options.cylinder_y_px = 230;
  options.px_per_mm = 4;  // the 20 mm cylinder and 30 mm of plume in a small image
  options.z_d_m = 0.5;    // larger shifts for a clear test
  const ConvectionScene scene(options);
  PatternOptions pattern_options;
  pattern_options.width_px = options.width_px;
  pattern_options.height_px = options.height_px;
  pattern_options.dot_diameter_px = 3;
  const BackgroundPattern pattern = generate_pattern(pattern_options);
  CameraModel camera;
  camera.noise_std = 0.005;
  const cv::Mat reference = scene.render_frame(pattern, camera, 5, false, 0);
  const cv::Mat frame = scene.render_frame(pattern, camera, 5, true, 1);
  ASSERT_EQ(frame.size(), cv::Size(320, 240));
  EXPECT_EQ(cv::countNonZero(scene.holder_mask()) > 0, true);

  const cv::Point2d probe = scene.image_position_px(0.003, 0.02);  // beside the centreline, 20 mm up
  fusion::EvaluatorOptions evaluator;
  evaluator.set_grid(32, 16);
  const auto result = fusion::probe_displacement(reference, frame, {probe}, evaluator, scene.holder_mask());
  ASSERT_EQ(result.field.size(), 1u);
  ASSERT_TRUE(result.field.vectors[0].valid());
  // The window averages the field; compare with the mean over the window.
  cv::Point2d mean(0, 0);
  for (int dy = -15; dy <= 16; ++dy) {
    for (int dx = -15; dx <= 16; ++dx) mean += scene.displacement_px(probe.x + dx - 0.5, probe.y + dy - 0.5, 5);
  }
  mean *= 1.0 / (32 * 32);
  ASSERT_GT(std::hypot(mean.x, mean.y), 0.3) << "too small a shift to mean anything";
  EXPECT_NEAR(result.field.vectors[0].u_px, mean.x, 0.1);
  EXPECT_NEAR(result.field.vectors[0].v_px, mean.y, 0.1);
}

}  // namespace
}  // namespace bosfuse::sim
