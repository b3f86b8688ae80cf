#include "sim/synthetic_pair.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace bosfuse::sim {
namespace {

double normal_cdf(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }

// Integrals of a unit-height 1-D Gaussian over pixels first..first+count-1.
void pixel_integrals(double centre, double sigma, int first, int count, std::vector<double>& out) {
  out.resize(static_cast<std::size_t>(count));
  double lower = normal_cdf((first - 0.5 - centre) / sigma);
  const double scale = std::sqrt(2 * std::numbers::pi) * sigma;
  for (int i = 0; i < count; ++i) {
    const double upper = normal_cdf((first + i + 0.5 - centre) / sigma);
    out[i] = scale * (upper - lower);
    lower = upper;
  }
}

cv::Mat quantise(const cv::Mat& unit, int bit_depth) {
  cv::Mat out;
  const double full_scale = bit_depth == 16 ? 65535.0 : 255.0;
  unit.convertTo(out, bit_depth == 16 ? CV_16U : CV_8U, full_scale);  // rounds and saturates
  return out;
}

cv::Mat finish(cv::Mat image, const PairOptions& options, std::uint64_t stream) {
  return camera_image(std::move(image), options.blur_sigma_px, options.noise_std, options.bit_depth, options.noise_seed,
                      stream);
}

}  // namespace

cv::Mat camera_image(cv::Mat image, double blur_sigma_px, double noise_std, int bit_depth, std::uint64_t noise_seed,
                     std::uint64_t stream) {
  if (blur_sigma_px > 0) cv::GaussianBlur(image, image, cv::Size(0, 0), blur_sigma_px);
  if (noise_std > 0) {
    cv::Mat noise(image.size(), CV_64F);
    cv::RNG rng(noise_seed * 2654435761u + stream);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_std);
    image += noise;
  }
  return quantise(image, bit_depth);
}

DisplacementModel DisplacementModel::uniform(double u_px, double v_px) {
  DisplacementModel m;
  m.u_px = u_px;
  m.v_px = v_px;
  return m;
}

DisplacementModel DisplacementModel::step(double step_x_px, double u_px, double v_px) {
  DisplacementModel m = uniform(u_px, v_px);
  m.kind = Kind::kStep;
  m.step_x_px = step_x_px;
  return m;
}

DisplacementModel DisplacementModel::sinusoid(double amplitude_px, double wavelength_px) {
  DisplacementModel m;
  m.kind = Kind::kSinusoid;
  m.amplitude_px = amplitude_px;
  m.wavelength_px = wavelength_px;
  return m;
}

DisplacementModel DisplacementModel::bump_gradient(double centre_x_px, double centre_y_px, double radius_px,
                                                   double peak_px) {
  DisplacementModel m;
  m.kind = Kind::kBumpGradient;
  m.centre_x_px = centre_x_px;
  m.centre_y_px = centre_y_px;
  m.radius_px = radius_px;
  m.amplitude_px = peak_px;
  return m;
}

cv::Point2d DisplacementModel::at(double x_px, double y_px) const {
  switch (kind) {
    case Kind::kUniform:
      return {u_px, v_px};
    case Kind::kStep:
      return x_px >= step_x_px ? cv::Point2d(u_px, v_px) : cv::Point2d(0, 0);
    case Kind::kSinusoid:
      return {0.0, amplitude_px * std::sin(2 * std::numbers::pi * x_px / wavelength_px)};
    case Kind::kBumpGradient: {
      // φ = h·exp(−r²/2s²); ∇φ peaks at r = s with |∇φ| = (h/s)·e^(−1/2).
      const double dx = x_px - centre_x_px, dy = y_px - centre_y_px, s = radius_px;
      const double g = amplitude_px * std::exp(0.5) * std::exp(-(dx * dx + dy * dy) / (2 * s * s));
      return {g * dx / s, g * dy / s};
    }
  }
  return {0, 0};
}

cv::Point2d DisplacementModel::window_mean(double x_px, double y_px, int window_px) const {
  cv::Point2d sum(0, 0);
  const double half = (window_px - 1) / 2.0;
  for (int j = 0; j < window_px; ++j) {
    for (int i = 0; i < window_px; ++i) sum += at(x_px - half + i, y_px - half + j);
  }
  return sum / double(window_px * window_px);
}

std::string PairOptions::Validate() const {
  if (auto problem = pattern.Validate(); !problem.empty()) return problem;
  if (!(noise_std >= 0 && noise_std < 1)) return "noise must be 0 to 1 of full scale";
  if (!(blur_sigma_px >= 0 && blur_sigma_px < 50)) return "blur sigma must be 0 to 50 px";
  if (bit_depth != 8 && bit_depth != 16) return fmt::format("bit depth must be 8 or 16, not {}", bit_depth);
  if (field.kind == DisplacementModel::Kind::kSinusoid && !(field.wavelength_px > 0))
    return "wavelength must be positive";
  if (field.kind == DisplacementModel::Kind::kBumpGradient && !(field.radius_px > 0))
    return "bump radius must be positive";
  return {};
}

cv::Mat render_dots(const BackgroundPattern& pattern, const DisplacementModel* displacement) {
  if (!displacement) return render_dots(pattern, DisplacementFunction{});
  return render_dots(pattern, [displacement](double x, double y) { return displacement->at(x, y); });
}

cv::Mat render_dots(const BackgroundPattern& pattern, const DisplacementFunction& displacement) {
  cv::Mat image(pattern.size, CV_64F, cv::Scalar(pattern.background_grey / 255.0));
  const double sigma = pattern.dot_diameter_px / 4;
  const double reach = 3.5 * sigma + 1;
  std::vector<double> along_x, along_y;
  for (const Dot& dot : pattern.dots) {
    cv::Point2d centre(dot.x_px, dot.y_px);
    if (displacement) centre += displacement(dot.x_px, dot.y_px);
    const int x0 = std::max(0, int(std::floor(centre.x - reach))),
              x1 = std::min(image.cols - 1, int(std::ceil(centre.x + reach)));
    const int y0 = std::max(0, int(std::floor(centre.y - reach))),
              y1 = std::min(image.rows - 1, int(std::ceil(centre.y + reach)));
    if (x1 < x0 || y1 < y0) continue;
    pixel_integrals(centre.x, sigma, x0, x1 - x0 + 1, along_x);
    pixel_integrals(centre.y, sigma, y0, y1 - y0 + 1, along_y);
    const double grey = dot.grey / 255.0;
    for (int py = y0; py <= y1; ++py) {
      double* row = image.ptr<double>(py);
      for (int px = x0; px <= x1; ++px) {
        const double alpha = std::min(1.0, along_x[px - x0] * along_y[py - y0]);
        row[px] += alpha * (grey - row[px]);
      }
    }
  }
  return image;
}

SyntheticPair render_pair(const PairOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  const BackgroundPattern pattern = generate_pattern(options.pattern);
  SyntheticPair pair;
  pair.truth = options.field;
  pair.reference = finish(render_dots(pattern, nullptr), options, 1);
  pair.measurement = finish(render_dots(pattern, &options.field), options, 2);
  return pair;
}

cv::Mat sensor_image(cv::Mat image, double noise_std, int bits, std::uint64_t noise_seed) {
  CV_Assert(image.type() == CV_64FC1 && bits >= 1 && bits <= 16);
  cv::Mat noise(image.size(), CV_64F);
  cv::RNG(noise_seed).fill(noise, cv::RNG::NORMAL, 0.0, noise_std);
  image += noise;
  const double levels = std::ldexp(1.0, bits) - 1, lsb = std::ldexp(1.0, 16 - bits);
  cv::Mat out(image.size(), CV_16U);
  for (int y = 0; y < image.rows; ++y) {
    const double* in = image.ptr<double>(y);
    auto* o = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < image.cols; ++x) {
      o[x] = static_cast<std::uint16_t>(std::clamp(std::round(in[x] * levels), 0.0, levels) * lsb);
    }
  }
  return out;
}

}  // namespace bosfuse::sim
