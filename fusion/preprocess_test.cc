#include "fusion/preprocess.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fusion/displacement_evaluator.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

// ---- scenes: dots moved by a known shift, lit as a camera might see them ----

// What lies in front of / behind the pattern and does not move with it.
struct Lighting {
  double contrast = 1;            // of the dots' range, around mid-grey
  cv::Mat gain;                   // CV_64F, multiplies the image; empty: 1
  cv::Mat background;             // CV_64F, added; empty: 0
  double noise_std = 0.01;        // of full scale
  int bits = 10;                  // stored in 16 bits, as a 10-bit camera's frames are
  double coverage = 0.5;          // of the pattern by dots
};

cv::Mat expose(cv::Mat image, const Lighting& lighting, std::uint64_t noise_seed) {
  image = 0.5 + lighting.contrast * (image - 0.5);
  if (!lighting.gain.empty()) image = image.mul(lighting.gain);
  if (!lighting.background.empty()) image += lighting.background;
  return sim::sensor_image(image, lighting.noise_std, lighting.bits, noise_seed);
}

struct Pair {
  cv::Mat reference, measurement;
  sim::DisplacementModel truth;
};

constexpr int kSizePx = 256;

Pair render(const sim::DisplacementModel& truth, const Lighting& lighting, std::uint64_t seed = 3) {
  sim::PatternOptions pattern;
  pattern.width_px = pattern.height_px = kSizePx;
  pattern.dot_diameter_px = 3;
  pattern.coverage = lighting.coverage;
  pattern.seed = seed;
  const sim::BackgroundPattern dots = sim::generate_pattern(pattern);
  return {expose(sim::render_dots(dots, nullptr), lighting, seed * 2 + 1),
          expose(sim::render_dots(dots, &truth), lighting, seed * 2 + 2), truth};
}

// Smooth blobs (Gaussian, σ `radius_px`) of `amplitude` at fixed places.
cv::Mat blobs(const std::vector<cv::Point2d>& centres, double radius_px, double amplitude) {
  cv::Mat field = cv::Mat::zeros(kSizePx, kSizePx, CV_64F);
  for (int y = 0; y < kSizePx; ++y) {
    auto* row = field.ptr<double>(y);
    for (int x = 0; x < kSizePx; ++x) {
      for (const auto& c : centres) {
        row[x] += amplitude * std::exp(-((x - c.x) * (x - c.x) + (y - c.y) * (y - c.y)) / (2 * radius_px * radius_px));
      }
    }
  }
  return field;
}

// The low-contrast camera: 10 bits, the dots' contrast scaled to
// 0.12, 0.4 % noise (as VectorUncertaintyCoverage.LowContrastTenBitCamera).
Lighting low_contrast() {
  Lighting l;
  l.contrast = 0.12;
  l.noise_std = 0.004;
  return l;
}

// A sparse pattern (a tenth covered) at the low contrast, under
// the noise of a camera at high gain (1 %): between the dots the windows
// hold little but noise, which the Wiener filter smooths away.
Lighting sparse_noisy_low_contrast() {
  Lighting l;
  l.contrast = 0.12;
  l.noise_std = 0.01;
  l.coverage = 0.1;
  return l;
}

// Light falling off from one corner to a fifth at the other, and a glow
// behind the pattern in blobs of about a window's size.
Lighting uneven_illumination() {
  Lighting l;
  l.gain = cv::Mat(kSizePx, kSizePx, CV_64F);
  for (int y = 0; y < kSizePx; ++y) {
    for (int x = 0; x < kSizePx; ++x) l.gain.at<double>(y, x) = 1.0 - 0.8 * (x + y) / (2.0 * kSizePx);
  }
  l.background = blobs({{40, 60}, {150, 90}, {90, 190}, {210, 210}, {200, 30}}, 9, 0.5);
  l.gain *= 0.6;
  l.noise_std = 0.003;  // so the light, not the noise, limits the error
  return l;
}

// ---- errors ----

struct Error {
  double rms_px = 0;
  std::size_t compared = 0;
};

// Against the window-averaged truth, over valid vectors a window from the edge.
Error error_of(const EvaluationResult& result, const sim::DisplacementModel& truth, int window_px) {
  Error e;
  double sum_sq = 0;
  for (const auto& vec : result.field.vectors) {
    const bool interior = vec.x_px >= window_px && vec.y_px >= window_px && vec.x_px < kSizePx - window_px &&
                          vec.y_px < kSizePx - window_px;
    if (!vec.valid() || !interior) continue;
    const cv::Point2d expected = truth.window_mean(vec.x_px, vec.y_px, window_px);
    sum_sq += std::pow(vec.u_px - expected.x, 2) + std::pow(vec.v_px - expected.y, 2);
    ++e.compared;
  }
  e.rms_px = e.compared ? std::sqrt(sum_sq / e.compared) : 1e9;
  return e;
}

// RMS error over a few sub-pixel shifts and pattern seeds.
struct Accuracy {
  double rms_px = 0;
  std::size_t valid = 0;  // interior vectors measured (the rest flagged)
};

Accuracy accuracy_with(Preprocessing method, const Lighting& lighting) {
  EvaluatorOptions options;
  options.preprocess.method = method;
  double sum_sq = 0;
  std::size_t compared = 0;
  const std::vector<cv::Point2d> shifts{{0.3, -0.2}, {0.75, 0.45}, {-0.55, 0.9}};
  std::uint64_t seed = 3;
  for (const auto& shift : shifts) {
    const Pair pair = render(sim::DisplacementModel::uniform(shift.x, shift.y), lighting, seed++);
    const Error e = error_of(evaluate_displacement(pair.reference, pair.measurement, options), pair.truth,
                             options.xcorr.window_px);
    EXPECT_GT(e.compared, 400u) << to_string(method);
    sum_sq += e.rms_px * e.rms_px * e.compared;
    compared += e.compared;
  }
  const double rms = std::sqrt(sum_sq / compared);
  ::testing::Test::RecordProperty(std::string(to_string(method)), std::to_string(rms));
  return {rms, compared};
}

double rms_with(Preprocessing method, const Lighting& lighting) { return accuracy_with(method, lighting).rms_px; }

// ---- names and options ----

TEST(PreprocessNames, EveryNameReadsBackAsItself) {
  for (const auto method : {Preprocessing::kNone, Preprocessing::kNormalize, Preprocessing::kHighpass,
                            Preprocessing::kMinmax, Preprocessing::kDenoise}) {
    EXPECT_EQ(parse_preprocessing(to_string(method)), method);
  }
  EXPECT_EQ(parse_preprocessing("clahe"), std::nullopt);
  EXPECT_EQ(parse_preprocessing(""), std::nullopt);
  EXPECT_EQ(preprocessing_names(), "none, normalize, highpass, minmax, denoise");
}

TEST(PreprocessOptions, DefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_EQ(PreprocessOptions{}.Validate(), "");
  PreprocessOptions even;
  even.normalize_window_px = 16;
  EXPECT_NE(even.Validate().find("normalize window 16"), std::string::npos) << even.Validate();
  PreprocessOptions tiny;
  tiny.minmax_window_px = 1;
  EXPECT_NE(tiny.Validate().find("min-max window 1"), std::string::npos) << tiny.Validate();
  PreprocessOptions sigma;
  sigma.highpass_sigma_px = std::nan("");
  EXPECT_NE(sigma.Validate().find("high-pass sigma"), std::string::npos);
  PreprocessOptions wiener;
  wiener.denoise_window_px = 4;
  EXPECT_NE(wiener.Validate().find("denoise window 4"), std::string::npos) << wiener.Validate();
  wiener.denoise_window_px = 3;
  wiener.denoise_noise_std = -0.01;
  EXPECT_NE(wiener.Validate().find("denoise noise std"), std::string::npos) << wiener.Validate();
  PreprocessOptions floor;
  floor.min_contrast = 0;
  EXPECT_NE(floor.Validate().find("min_contrast"), std::string::npos);
  EXPECT_THROW(preprocess(cv::Mat::zeros(32, 32, CV_8U), sigma), std::invalid_argument);
  EvaluatorOptions evaluator;
  evaluator.preprocess = even;
  EXPECT_NE(evaluator.Validate().find("normalize window"), std::string::npos);
}

// ---- what each filter does to an image ----

TEST(Preprocess, NoneReturnsTheImageItself) {
  const cv::Mat image = cv::Mat::ones(20, 20, CV_16U) * 1000;
  const cv::Mat out = preprocess(image, PreprocessOptions{});
  EXPECT_EQ(out.data, image.data);
}

TEST(Preprocess, EveryFilterFlattensASmoothBackgroundAndKeepsADot) {
  // A ramp from 0.2 to 0.8 with one dark dot: after each filter the ramp is
  // gone (mid-grey far from the dot) and the dot is still darker than it.
  cv::Mat image(64, 96, CV_32F);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 96; ++x) image.at<float>(y, x) = 0.2f + 0.6f * x / 95.0f;
  }
  cv::circle(image, {48, 50}, 2, 0.0, cv::FILLED);
  for (const auto method : {Preprocessing::kNormalize, Preprocessing::kHighpass, Preprocessing::kMinmax}) {
    PreprocessOptions options;
    options.method = method;
    const cv::Mat out = preprocess(image, options);
    ASSERT_EQ(out.type(), CV_32FC1);
    // Far from the dot and the side edges the ramp is linear, and a local
    // mean (or the middle of a local min and max) of a linear ramp is the
    // ramp: nothing is left of it.
    const float left = out.at<float>(10, 20), right = out.at<float>(10, 70);
    EXPECT_NEAR(left, 0.5, 0.02) << to_string(method);
    EXPECT_NEAR(right, 0.5, 0.02) << to_string(method);
    EXPECT_LT(out.at<float>(50, 48), std::min(left, right) - 0.1) << to_string(method);
  }
}

TEST(Preprocess, SixteenBitDepthIsKeptBeyondEightBits) {
  // Steps of 16 in 16 bits (a 12-bit camera's LSB) are below one 8-bit
  // grey level; after normalisation they still differ.
  cv::Mat image(32, 32, CV_16U);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) image.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(30000 + 16 * ((x + y) % 3));
  }
  PreprocessOptions options;
  options.method = Preprocessing::kNormalize;
  options.min_contrast = 1e-5;
  const cv::Mat out = preprocess(image, options);
  EXPECT_GT(std::abs(out.at<float>(16, 16) - out.at<float>(16, 17)), 0.05);
}

TEST(Preprocess, MaskedPixelsDoNotLeakIntoTheirNeighbours) {
  // The same textured image twice, once with a bright block under the mask:
  // outside the mask every filter gives the same pixels, which it could not
  // if the block entered a local mean, std, min or max.
  cv::Mat texture(64, 64, CV_32F);
  cv::RNG(5).fill(texture, cv::RNG::UNIFORM, 0.3, 0.5);
  cv::Mat with_block = texture.clone();
  with_block(cv::Rect(24, 24, 16, 16)).setTo(1.0);
  cv::Mat mask = cv::Mat::zeros(64, 64, CV_8U);
  mask(cv::Rect(24, 24, 16, 16)).setTo(255);
  cv::Mat dimmed = texture.clone();
  dimmed(cv::Rect(24, 24, 16, 16)).setTo(0.0);
  for (const auto method :
       {Preprocessing::kNormalize, Preprocessing::kHighpass, Preprocessing::kMinmax, Preprocessing::kDenoise}) {
    PreprocessOptions options;
    options.method = method;
    const cv::Mat a = preprocess(with_block, options, mask), b = preprocess(dimmed, options, mask);
    cv::Mat difference;
    cv::absdiff(a, b, difference);
    EXPECT_LT(cv::norm(difference, cv::NORM_INF), 1e-5) << to_string(method);
    EXPECT_FLOAT_EQ(a.at<float>(30, 30), 0.5f) << to_string(method);  // masked: mid-grey
    // And the block would have leaked without the mask.
    cv::absdiff(preprocess(with_block, options), preprocess(dimmed, options), difference);
    EXPECT_GT(difference.at<float>(23, 23), 1e-3) << to_string(method);
  }
}

TEST(Preprocess, AFeaturelessImageStaysFlatRatherThanNoiseBlownUp) {
  cv::Mat image(64, 64, CV_32F);
  cv::RNG(9).fill(image, cv::RNG::NORMAL, 0.5, 0.0002);  // sensor noise alone, a tenth of min_contrast
  for (const auto method : {Preprocessing::kNormalize, Preprocessing::kMinmax}) {
    PreprocessOptions options;
    options.method = method;
    cv::Scalar mean, deviation;
    cv::meanStdDev(preprocess(image, options), mean, deviation);
    EXPECT_LT(deviation[0], method == Preprocessing::kNormalize ? 0.125 * 0.2 : 0.2) << to_string(method);
  }
}

// The Wiener filter's noise estimate reads the noise, not the dots: on a
// dense pattern of the low contrast its std is within a factor 2 of
// the true one (the mean local variance, MATLAB's, is 5× the std there).
TEST(Preprocess, TheNoiseEstimateReadsTheSensorNoiseBesideTheDots) {
  for (const double noise : {0.004, 0.01, 0.02}) {
    Lighting lighting = low_contrast();
    lighting.noise_std = noise;
    const Pair pair = render(sim::DisplacementModel::uniform(0, 0), lighting);
    cv::Mat image;
    pair.reference.convertTo(image, CV_32F, 1.0 / 65535);
    const double estimated = estimate_noise_std(image);
    EXPECT_GT(estimated, 0.9 * noise) << noise;
    EXPECT_LT(estimated, 2.0 * noise) << noise;
  }
  // Noise alone: the estimate is the noise.
  cv::Mat flat(128, 128, CV_32F);
  cv::RNG(4).fill(flat, cv::RNG::NORMAL, 0.5, 0.01);
  EXPECT_NEAR(estimate_noise_std(flat), 0.01, 0.0005);
}

TEST(Preprocess, DenoiseSmoothsNoiseAndKeepsTheDots) {
  // A flat patch of noise beside a dark dot: the noise's std falls, the
  // dot keeps most of its depth.
  cv::Mat image(64, 64, CV_32F);
  cv::RNG(6).fill(image, cv::RNG::NORMAL, 0.5, 0.01);
  cv::circle(image, {48, 32}, 2, 0.3, cv::FILLED);
  PreprocessOptions options;
  options.method = Preprocessing::kDenoise;
  const cv::Mat out = preprocess(image, options);
  ASSERT_EQ(out.type(), CV_32FC1);
  cv::Scalar mean_before, std_before, mean_after, std_after;
  const cv::Rect flat(4, 4, 24, 56);
  cv::meanStdDev(image(flat), mean_before, std_before);
  cv::meanStdDev(out(flat), mean_after, std_after);
  EXPECT_LT(std_after[0], 0.6 * std_before[0]);
  EXPECT_NEAR(mean_after[0], mean_before[0], 0.002);  // the levels are kept
  EXPECT_LT(out.at<float>(32, 48), 0.36f);
}

TEST(Preprocess, ABadMaskIsNamed) {
  PreprocessOptions options;
  options.method = Preprocessing::kHighpass;
  try {
    preprocess(cv::Mat::zeros(32, 32, CV_8U), options, cv::Mat::zeros(16, 16, CV_8U));
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mask size 16x16"), std::string::npos) << e.what();
  }
}

// ---- each filter helps where it should ----

// A pattern lit evenly but with little contrast is limited by the sensor's
// noise, which no filter of these removes (docs/BENCHMARKS.md,
// "Preprocessing"): they must not make it much worse (measured: normalize
// and highpass +1–3 %, minmax, whose 9 px window is tight for the noise, +6 %).
TEST(PreprocessHelps, NoFilterHarmsTheLowContrastTenBitPair) {
  const double none = rms_with(Preprocessing::kNone, low_contrast());
  for (const auto method :
       {Preprocessing::kNormalize, Preprocessing::kHighpass, Preprocessing::kMinmax, Preprocessing::kDenoise}) {
    const double filtered = rms_with(method, low_contrast());
    const double bound = method == Preprocessing::kMinmax ? 1.10 : 1.05;
    EXPECT_LT(filtered, bound * none) << "none " << none << " px, " << to_string(method) << " " << filtered << " px";
  }
}

// The Wiener filter where sensor noise fills the windows between sparse
// dots: it lowers the error against the image as it is (measured 0.149
// against 0.168 px, and 2281 against 2202 vectors measured). The brief's dense low-contrast pair is in
// docs/BENCHMARKS.md: there it changes little.
TEST(PreprocessHelps, DenoiseBeatsNoneOnASparseNoisyLowContrastPair) {
  const Accuracy none = accuracy_with(Preprocessing::kNone, sparse_noisy_low_contrast());
  const Accuracy denoised = accuracy_with(Preprocessing::kDenoise, sparse_noisy_low_contrast());
  const std::string measured = fmt::format("none {:.4f} px on {} vectors, denoise {:.4f} px on {}", none.rms_px,
                                           none.valid, denoised.rms_px, denoised.valid);
  EXPECT_LT(denoised.rms_px, 0.95 * none.rms_px) << measured;
  EXPECT_GE(denoised.valid, none.valid) << measured;
}

// Light falling off fivefold across the frame and a glow behind the
// pattern: each filter removes what none leaves in the windows. Without a
// filter the windows the glow washes out are flagged (no clear peak), so
// the gain shows in both: more vectors measured, and a lower error on them.
TEST(PreprocessHelps, EveryFilterBeatsNoneUnderUnevenIllumination) {
  const Accuracy none = accuracy_with(Preprocessing::kNone, uneven_illumination());
  for (const auto method : {Preprocessing::kNormalize, Preprocessing::kHighpass, Preprocessing::kMinmax}) {
    const Accuracy filtered = accuracy_with(method, uneven_illumination());
    const std::string measured = fmt::format("none {:.4f} px on {} vectors, {} {:.4f} px on {}", none.rms_px,
                                             none.valid, to_string(method), filtered.rms_px, filtered.valid);
    EXPECT_LT(filtered.rms_px, 0.95 * none.rms_px) << measured;
    EXPECT_GT(filtered.valid, none.valid) << measured;
  }
}

TEST(PreprocessHelps, TheEvaluatorPreprocessesTheMeasurementAsTheReference) {
  // One evaluator over two frames equals the one-shot evaluation of each,
  // and probes take the same preprocessing (same vectors at the probes).
  const Lighting lighting = uneven_illumination();
  const Pair first = render(sim::DisplacementModel::uniform(0.4, 0.1), lighting);
  EvaluatorOptions options;
  options.preprocess.method = Preprocessing::kHighpass;
  DisplacementEvaluator evaluator(first.reference, options);
  const auto many = evaluator.evaluate(first.measurement);
  const auto once = evaluate_displacement(first.reference, first.measurement, options);
  ASSERT_EQ(many.field.vectors.size(), once.field.vectors.size());
  for (std::size_t i = 0; i < once.field.vectors.size(); ++i) {
    EXPECT_EQ(many.field.vectors[i].u_px, once.field.vectors[i].u_px);
  }
  const auto probed = evaluator.probe(first.measurement, {{128, 128}});
  ASSERT_EQ(probed.field.vectors.size(), 1u);
  EXPECT_NEAR(probed.field.vectors[0].u_px, 0.4, 0.05);
  options.preprocess.method = Preprocessing::kNone;
  const auto unprocessed = probe_displacement(first.reference, first.measurement, {{128, 128}}, options);
  EXPECT_NE(unprocessed.field.vectors[0].u_px, probed.field.vectors[0].u_px);
}

TEST(PreprocessHelps, ABadMeasurementIsNamedAsSuch) {
  const Pair pair = render(sim::DisplacementModel::uniform(0.4, 0.1), low_contrast());
  EvaluatorOptions options;
  options.preprocess.method = Preprocessing::kNormalize;
  DisplacementEvaluator evaluator(pair.reference, options);
  try {
    evaluator.evaluate(cv::Mat());
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("measurement image is empty"), std::string::npos) << e.what();
  }
  EXPECT_THROW(evaluator.evaluate(cv::Mat::zeros(10, 10, CV_8U)), std::invalid_argument);
}

}  // namespace
}  // namespace bosfuse::fusion
