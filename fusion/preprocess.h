#pragma once
// Image preprocessing before the displacement evaluation, the filters PIV
// users know from PIVlab: they even out what the background pattern does not
// move — uneven illumination, a glow or shadow behind the pattern, contrast
// that differs across the frame — so every window's correlation weighs the
// dots, not the light. Use one when the pattern is lit unevenly, has
// saturated or dark patches, or has little contrast; on a well-lit pattern
// `none` (the default) is as accurate and costs nothing. The evaluator
// (displacement_evaluator.h) applies the same option to the reference once
// and to every measurement, so every command gets it through one place.
//
//   none      — the image as the camera gave it.
//   normalize — local contrast normalisation: (I − local mean) / local std
//               over a square window (normalize_window_px).
//   highpass  — background subtraction: I − Gaussian blur of σ highpass_sigma_px.
//   minmax    — min–max normalisation: (I − local min) / (local max − local
//               min) over a square window (minmax_window_px), the envelopes
//               smoothed over the same window (PIVlab's "min-max filter").
//   denoise   — adaptive Wiener filter (MATLAB's wiener2, PIVlab's "Wiener2
//               denoise"): over a square window (denoise_window_px) of local
//               mean μ and variance σ², I' = μ + max(σ² − ν, 0) / max(σ², ν)
//               · (I − μ), where ν is the sensor noise's variance
//               (denoise_noise_std², or estimated from the image, see
//               estimate_noise_std). Smooths where the image holds little
//               more than noise, keeps the dots where they stand out.
//
// Every option returns CV_32FC1 in units of full scale (most pixels within
// [0, 1]), centred on mid-grey (denoise: the image's own levels), which
// every evaluator takes as it takes a camera's float image; float32 keeps a
// 16-bit sensor's precision. Masked
// pixels (non-zero in the mask) do not enter their neighbours' statistics:
// local sums are normalised by the unmasked weight, and the masked pixels
// themselves come out at mid-grey.

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::fusion {

enum class Preprocessing { kNone, kNormalize, kHighpass, kMinmax, kDenoise };

// The one name table, used by the commands and the stored settings.
std::string_view to_string(Preprocessing preprocessing);
std::optional<Preprocessing> parse_preprocessing(std::string_view name);
// "none, normalize, highpass, minmax, denoise", for messages and help.
std::string preprocessing_names();

struct PreprocessOptions {
  Preprocessing method = Preprocessing::kNone;
  int normalize_window_px = 15;    // odd, 3..255: spans several dots of 3 px, below a 16 px window
  double highpass_sigma_px = 3;    // 0.5..64: above the dots' size, below the window's
  int minmax_window_px = 9;        // odd, 3..255
  // Local std (normalize) and local max − min (minmax) below this fraction
  // of full scale count as this much: a featureless patch stays flat rather
  // than have its sensor noise blown up to full contrast.
  double min_contrast = 0.002;
  int denoise_window_px = 3;       // odd, 3..255: MATLAB wiener2's default, a 3 px dot's size
  // The sensor noise's standard deviation, of full scale; 0: estimated from
  // each image (estimate_noise_std).
  double denoise_noise_std = 0;

  std::string Validate() const;  // empty when valid
};

// `image`: 8- or 16-bit or float (as image_input.h takes them), grey or
// colour. With kNone the image is returned as it is (no copy). Throws
// std::invalid_argument on bad options or a mask of another size. A colour
// image's conversion is warned of into `warnings` (nullptr: silently).
cv::Mat preprocess(const cv::Mat& image, const PreprocessOptions& options, const cv::Mat& mask = {},
                   std::vector<std::string>* warnings = nullptr);

// The standard deviation of white sensor noise in `image` (CV_32F, full
// scale), by Immerkær's estimator (J. Immerkær, "Fast noise variance
// estimation", CVIU 64(2):300, 1996): the mean |I ∗ L| of a Laplacian
// difference L that cancels a locally planar image, × √(π/2)/6. Over the
// pixels whose 3×3 neighbourhood `weight` (empty: all) leaves unmasked.
// MATLAB's wiener2 takes the mean local variance instead, which on a dense
// dot pattern is the dots' contrast, not the noise (25× the noise variance
// on the low-contrast 10-bit pair, where its filter then blurs the dots);
// this estimate reads 1.1–1.6× the true noise there.
double estimate_noise_std(const cv::Mat& image, const cv::Mat& weight = {});

}  // namespace bosfuse::fusion
