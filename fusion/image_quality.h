#pragma once
// How well a captured background image reproduces the digital pattern it was
// printed from (Gojani & Obayashi 2012, after Wang & Bovik 2002). Use it
// before an experiment to judge camera, lens and lighting: cross-correlation
// failed on images with Q_mod ≈ 0.01 and worked on Q_mod ≈ 0.7.
//
//   Q_L = 2·μx·μy / (μx² + μy²)      luminance: equal mean brightness → 1
//   Q_C = 2·σx·σy / (σx² + σy²)      contrast: equal spread of grey levels → 1
//   Q_mod = Q_L·Q_C
//   Q (Wang–Bovik) = σxy/(σx·σy) · Q_L · Q_C, averaged over sliding 8×8 windows
//
// σ is the sample standard deviation (the paper's printed formula omits the
// squares and the root; this is the corrected one). Q_mod drops the
// correlation term, which is near 0 for a random pattern whose camera image
// is not registered to the file. Degenerate cases are defined, never NaN:
// two flat windows have Q_C = 1 and correlation 1, a flat window against a
// textured one Q_C = 0; two black windows Q_L = 1.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace bosfuse::fusion {

struct QualityIndex {
  double q_l = 0;
  double q_c = 0;
  double q_mod = 0;
  double mean_image = 0;  // of full scale
  double mean_reference = 0;
  double std_image = 0;  // sample standard deviation, of full scale
  double std_reference = 0;
};

struct QualityOptions {
  int window_px = 8;  // sliding window of the universal index and the local map

  std::string Validate() const;  // empty when valid
};

struct QualityReport {
  QualityIndex global;
  // Colour images converted, a reference resized: for the caller to log
  // (fusion/ logs nothing), in the order they arose.
  std::vector<std::string> warnings;
  double universal_index = 0;  // Wang–Bovik Q, mean over sliding windows
  double mean_local_q_mod = 0;
  cv::Mat local_q_mod;  // CV_64F, one value per window position ((rows−w+1)×(cols−w+1))
};

// Global Q_L, Q_C, Q_mod over whole images, which may differ in size.
QualityIndex modified_quality_index(const cv::Mat& image, const cv::Mat& reference);

// What the global index compares of one image: its grey levels' mean and
// sample standard deviation, of full scale. Computed on the image as stored
// (8 or 16 bit) without a float copy, so a live check can prepare its
// reference's once and compare every frame with it.
struct GreyMoments {
  double mean = 0;
  double std = 0;
  std::vector<std::string> warnings;  // a colour image's conversion, for the caller to log
};
GreyMoments grey_moments(const cv::Mat& image, const std::string& name = "image");
QualityIndex modified_quality_index(const GreyMoments& image, const GreyMoments& reference);

// Everything, sliding-window measures included. A reference of another size
// is resized to the image's (with a warning): a printed pattern file rarely
// matches the camera's pixel count.
QualityReport assess_quality(const cv::Mat& image, const cv::Mat& reference, const QualityOptions& options = {});

}  // namespace bosfuse::fusion
