#pragma once
// Synthetic BOS image pairs with a known displacement field, for testing and
// benchmarking evaluators. The dots of a random background (see
// background_pattern.h) are moved by the field and both images are rendered
// from the dot positions, each pixel integrating the dot's intensity over its
// area (Gaussian dots, integrated exactly with erf) — never by interpolating
// a rendered image, which would hide the evaluator's own interpolation error
// inside the "truth". Optics blur, sensor noise and quantisation to 8 or 16
// bits follow, in that order.
//
// The field is defined in reference coordinates: the dot centred at (x, y)
// in the reference is centred at (x + u(x, y), y + v(x, y)) in the
// measurement image, as DESIGN.md defines displacement.

#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "sim/background_pattern.h"

namespace bosfuse::sim {

struct DisplacementModel {
  enum class Kind { kUniform, kStep, kSinusoid, kBumpGradient };
  Kind kind = Kind::kUniform;
  double u_px = 0;  // uniform shift, or the shift right of the step
  double v_px = 0;
  double step_x_px = 64;      // step: x ≥ step_x_px is shifted by (u, v)
  double amplitude_px = 1;    // sinusoid: v = A·sin(2π·x/λ); bump: largest |shift|
  double wavelength_px = 64;  // sinusoid
  double centre_x_px = 0;     // bump centre
  double centre_y_px = 0;
  double radius_px = 32;  // bump: the shift peaks at this distance from the centre

  static DisplacementModel uniform(double u_px, double v_px);
  static DisplacementModel step(double step_x_px, double u_px, double v_px);
  static DisplacementModel sinusoid(double amplitude_px, double wavelength_px);
  // The gradient of a Gaussian bump, pointing outwards (what BOS sees of a cold
  // spot; a hot spot pulls the background inwards: give a negative peak).
  static DisplacementModel bump_gradient(double centre_x_px, double centre_y_px, double radius_px, double peak_px);

  cv::Point2d at(double x_px, double y_px) const;
  // Mean over a window of `window_px` centred at (x, y): what a window-based
  // evaluator can at best return there.
  cv::Point2d window_mean(double x_px, double y_px, int window_px) const;
};

struct PairOptions {
  PatternOptions pattern;  // size, dot size, coverage, grey levels, seed
  DisplacementModel field;
  double noise_std = 0.01;   // Gaussian sensor noise, fraction of full scale
  double blur_sigma_px = 0;  // Gaussian optics blur, applied to both images
  int bit_depth = 8;         // 8 or 16
  std::uint64_t noise_seed = 7;

  std::string Validate() const;  // empty when valid
};

struct SyntheticPair {
  cv::Mat reference;  // CV_8UC1 or CV_16UC1
  cv::Mat measurement;
  DisplacementModel truth;
};

SyntheticPair render_pair(const PairOptions& options);

// Where the dot centred at (x, y) in the reference has moved: (u, v) in px.
using DisplacementFunction = std::function<cv::Point2d(double x_px, double y_px)>;

// Gaussian dots (σ = diameter/4) integrated over each pixel, painted in
// order; full scale is 1.0 (grey 255). CV_64FC1. No displacement: the reference.
cv::Mat render_dots(const BackgroundPattern& pattern, const DisplacementFunction& displacement);
cv::Mat render_dots(const BackgroundPattern& pattern, const DisplacementModel* displacement);

// The camera after the optics: blur, Gaussian noise (fraction of full scale,
// seeded by noise_seed and stream) and quantisation of a CV_64F image with
// full scale 1.0 to 8 or 16 bits.
cv::Mat camera_image(cv::Mat image, double blur_sigma_px, double noise_std, int bit_depth, std::uint64_t noise_seed,
                     std::uint64_t stream);

// A sensor of `bits` (1..16) whose frames are stored in 16 bits, as a 10-
// or 12-bit camera's are: Gaussian noise (fraction of full scale, seeded by
// noise_seed) added to a CV_64F image with full scale 1.0, which is then
// clamped and rounded to 2^bits − 1 levels held in the CV_16U's top bits.
cv::Mat sensor_image(cv::Mat image, double noise_std, int bits, std::uint64_t noise_seed);

}  // namespace bosfuse::sim
