#include "fusion/preprocess.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "fusion/image_input.h"

namespace bosfuse::fusion {
namespace {

constexpr std::array<std::pair<Preprocessing, std::string_view>, 5> kNames{{{Preprocessing::kNone, "none"},
                                                                             {Preprocessing::kNormalize, "normalize"},
                                                                             {Preprocessing::kHighpass, "highpass"},
                                                                             {Preprocessing::kMinmax, "minmax"},
                                                                             {Preprocessing::kDenoise, "denoise"}}};

// Local z-scores are mapped to 0.5 + z/8, so ±4 σ span full scale (an
// 8-bit conversion, as optical flow makes, clips only beyond that).
constexpr double kZScoreScale = 0.125;
constexpr float kMidGrey = 0.5f;

// The image and the weight of its unmasked pixels (1, or 0 under the mask).
struct Weighted {
  cv::Mat image;   // CV_32F, [0, 1]; masked pixels 0
  cv::Mat weight;  // CV_32F; empty without a mask
};

Weighted weighted_input(const cv::Mat& image, const cv::Mat& mask, std::vector<std::string>* warnings) {
  Weighted in;
  in.image = to_grey_unit_float(image, "image to preprocess", warnings);
  if (mask.empty()) return in;
  if (mask.size() != image.size()) {
    throw std::invalid_argument(fmt::format("preprocessing: mask size {}x{} differs from the image size {}x{}",
                                            mask.cols, mask.rows, image.cols, image.rows));
  }
  const cv::Mat excluded = to_exclusion_mask(mask);
  in.weight = cv::Mat::ones(image.size(), CV_32F);
  in.weight.setTo(0, excluded);
  in.image.setTo(0, excluded);
  return in;
}

// The mean of `values` over the neighbourhood `smooth` averages, counting
// only unmasked pixels (a masked pixel's value does not leak into it).
template <typename Smooth>
cv::Mat local_mean(const cv::Mat& values, const cv::Mat& weight, const Smooth& smooth) {
  cv::Mat sum;
  smooth(values, sum);
  if (weight.empty()) return sum;
  cv::Mat weight_sum;
  smooth(weight, weight_sum);
  cv::max(weight_sum, 1e-6, weight_sum);  // wholly masked neighbourhoods: the sum is 0 as well
  return sum / weight_sum;
}

// Masked pixels come out neutral, so they add nothing to a window's correlation.
cv::Mat neutral_under_mask(cv::Mat out, const cv::Mat& weight) {
  if (!weight.empty()) out.setTo(kMidGrey, weight == 0);
  return out;
}

cv::Mat normalize_contrast(const Weighted& in, const PreprocessOptions& options) {
  const cv::Size box(options.normalize_window_px, options.normalize_window_px);
  const auto smooth = [&](const cv::Mat& src, cv::Mat& dst) { cv::boxFilter(src, dst, CV_32F, box); };
  // Centred on the frame's mean first, so E[I²] − E[I]² does not cancel
  // digits in float at low contrast.
  const double centre = cv::mean(in.image, in.weight.empty() ? cv::noArray() : cv::Mat(in.weight != 0))[0];
  cv::Mat centred = in.image - centre;
  if (!in.weight.empty()) centred = centred.mul(in.weight);
  const cv::Mat mean = local_mean(centred, in.weight, smooth);
  const cv::Mat mean_square = local_mean(centred.mul(centred), in.weight, smooth);
  cv::Mat variance = mean_square - mean.mul(mean);
  cv::max(variance, options.min_contrast * options.min_contrast, variance);
  cv::Mat deviation;
  cv::sqrt(variance, deviation);
  cv::Mat out = (centred - mean) / deviation * kZScoreScale + kMidGrey;
  return neutral_under_mask(out, in.weight);
}

cv::Mat subtract_background(const Weighted& in, const PreprocessOptions& options) {
  const double sigma = options.highpass_sigma_px;
  const auto smooth = [&](const cv::Mat& src, cv::Mat& dst) { cv::GaussianBlur(src, dst, cv::Size(0, 0), sigma); };
  cv::Mat out = in.image - local_mean(in.image, in.weight, smooth) + kMidGrey;
  return neutral_under_mask(out, in.weight);
}

cv::Mat normalize_min_max(const Weighted& in, const PreprocessOptions& options) {
  const int n = options.minmax_window_px;
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(n, n));
  cv::Mat for_max = in.image, for_min = in.image;
  if (!in.weight.empty()) {
    // Masked pixels below every value for the max and above for the min: never an extreme.
    const cv::Mat excluded = in.weight == 0;
    for_max = in.image.clone();
    for_max.setTo(-1, excluded);
    for_min = in.image.clone();
    for_min.setTo(2, excluded);
  }
  cv::Mat upper, lower;
  cv::dilate(for_max, upper, square);
  cv::erode(for_min, lower, square);
  // The raw envelopes step wherever a dot enters or leaves the square;
  // smoothed over it they follow the illumination, not the dots.
  const cv::Size box(n, n);
  const auto smooth = [&](const cv::Mat& src, cv::Mat& dst) { cv::boxFilter(src, dst, CV_32F, box); };
  cv::Mat envelope_weight;
  if (!in.weight.empty()) {
    envelope_weight = cv::Mat::zeros(in.image.size(), CV_32F);
    envelope_weight.setTo(1, upper >= lower);  // not wholly masked
    upper = upper.mul(envelope_weight);
    lower = lower.mul(envelope_weight);
  }
  upper = local_mean(upper, envelope_weight, smooth);
  lower = local_mean(lower, envelope_weight, smooth);
  cv::Mat range = upper - lower;
  cv::max(range, options.min_contrast, range);
  cv::Mat out = (in.image - lower) / range;
  return neutral_under_mask(out, in.weight);
}

// MATLAB's wiener2 on the unmasked pixels: the local mean where the local
// variance is no more than the noise's, the pixel itself where it is far more.
cv::Mat denoise_wiener(const Weighted& in, const PreprocessOptions& options) {
  const cv::Size box(options.denoise_window_px, options.denoise_window_px);
  const auto smooth = [&](const cv::Mat& src, cv::Mat& dst) { cv::boxFilter(src, dst, CV_32F, box); };
  const double noise_std =
      options.denoise_noise_std > 0 ? options.denoise_noise_std : estimate_noise_std(in.image, in.weight);
  // A noiseless image (ν = 0) passes unchanged; the floor keeps 0/0 out of a flat patch.
  const double noise_variance = std::max(noise_std * noise_std, 1e-12);
  // Centred first, as normalize_contrast, so E[I²] − E[I]² keeps its digits in float.
  const double centre = cv::mean(in.image, in.weight.empty() ? cv::noArray() : cv::Mat(in.weight != 0))[0];
  cv::Mat centred = in.image - centre;
  if (!in.weight.empty()) centred = centred.mul(in.weight);
  const cv::Mat mean = local_mean(centred, in.weight, smooth);
  cv::Mat variance = local_mean(centred.mul(centred), in.weight, smooth) - mean.mul(mean);
  cv::max(variance, 0, variance);
  cv::Mat signal_variance = variance - noise_variance;
  cv::max(signal_variance, 0, signal_variance);
  cv::max(variance, noise_variance, variance);
  cv::Mat out = mean + signal_variance.mul(centred - mean) / variance + centre;
  return neutral_under_mask(out, in.weight);
}

}  // namespace

double estimate_noise_std(const cv::Mat& image, const cv::Mat& weight) {
  // Two Laplacians 2 px apart: a plane and a quadratic-free patch give 0,
  // white noise of σ gives a zero-mean normal of σ·6 (the kernel's L2 norm).
  const cv::Mat kernel = (cv::Mat_<float>(3, 3) << 1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat response;
  cv::filter2D(image, response, CV_32F, kernel, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  response = cv::abs(response);
  // The border rows and columns see a reflected neighbour: left out, as are
  // pixels with a masked neighbour.
  cv::Mat counted = cv::Mat::zeros(image.size(), CV_8U);
  if (image.rows > 2 && image.cols > 2) counted(cv::Rect(1, 1, image.cols - 2, image.rows - 2)).setTo(1);
  if (!weight.empty()) {
    cv::Mat unmasked;
    cv::erode(weight, unmasked, cv::Mat::ones(3, 3, CV_8U), cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
    counted.setTo(0, unmasked == 0);
  }
  if (cv::countNonZero(counted) == 0) return 0;
  constexpr double kPi = 3.14159265358979323846;
  return std::sqrt(kPi / 2) / 6 * cv::mean(response, counted)[0];
}

std::string_view to_string(Preprocessing preprocessing) {
  for (const auto& [value, name] : kNames) {
    if (value == preprocessing) return name;
  }
  return "unknown";
}

std::optional<Preprocessing> parse_preprocessing(std::string_view name) {
  for (const auto& [value, known] : kNames) {
    if (known == name) return value;
  }
  return std::nullopt;
}

std::string preprocessing_names() {
  std::string names;
  for (const auto& [value, name] : kNames) names += (names.empty() ? "" : ", ") + std::string(name);
  return names;
}

std::string PreprocessOptions::Validate() const {
  const auto odd_window = [](int px) { return px >= 3 && px <= 255 && px % 2 == 1; };
  if (!odd_window(normalize_window_px)) {
    return fmt::format("preprocessing: normalize window {} px must be odd, 3..255", normalize_window_px);
  }
  if (!odd_window(minmax_window_px)) {
    return fmt::format("preprocessing: min-max window {} px must be odd, 3..255", minmax_window_px);
  }
  if (!(highpass_sigma_px >= 0.5 && highpass_sigma_px <= 64)) {
    return fmt::format("preprocessing: high-pass sigma {} px must lie in 0.5..64", highpass_sigma_px);
  }
  if (!odd_window(denoise_window_px)) {
    return fmt::format("preprocessing: denoise window {} px must be odd, 3..255", denoise_window_px);
  }
  if (!(denoise_noise_std >= 0 && denoise_noise_std < 1)) {
    return fmt::format("preprocessing: denoise noise std {} must lie in [0, 1) of full scale (0: estimated)",
                       denoise_noise_std);
  }
  if (!(min_contrast > 0 && min_contrast < 1)) {
    return fmt::format("preprocessing: min_contrast {} must lie in (0, 1) of full scale", min_contrast);
  }
  return {};
}

cv::Mat preprocess(const cv::Mat& image, const PreprocessOptions& options, const cv::Mat& mask,
                   std::vector<std::string>* warnings) {
  if (const std::string problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  if (options.method == Preprocessing::kNone) return image;
  const Weighted in = weighted_input(image, mask, warnings);
  switch (options.method) {
    case Preprocessing::kNormalize:
      return normalize_contrast(in, options);
    case Preprocessing::kHighpass:
      return subtract_background(in, options);
    case Preprocessing::kMinmax:
      return normalize_min_max(in, options);
    case Preprocessing::kDenoise:
      return denoise_wiener(in, options);
    case Preprocessing::kNone:
      break;
  }
  return image;
}

}  // namespace bosfuse::fusion
