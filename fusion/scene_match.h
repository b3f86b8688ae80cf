#pragma once
// Whether an image shows the same background as a reference, and, if it
// does, how good its contrast is: the verdict `quality` prints and the check
// `evaluate` and `process` make before they trust a pair. Use a SceneMatcher
// when one reference meets many frames (it keeps the reference's moments);
// match_scene for one pair.
//
// The quantity tested is a registration test, not the paper's Q_mod (which
// compares only brightness and contrast and rates an unrelated pattern 0.97):
// both images are low-pass filtered (Gaussian, blur_sigma_px) and cut into
// tiles; each tile's normalised correlation with the image is maximised over
// integer shifts within ±max_shift_px, and the median over the tiles is the
// scene correlation. A BOS displacement is a shift of a few px, smooth over a
// tile, so the maximum over shifts finds it, and the blur makes a sub-pixel
// remainder or a gradient across the tile cost little: a matching pair with
// noise scores 0.97-1.00 at uniform shifts of 0, 2 and 6.5 px, and 0.77
// behind a plume whose shift changes by 6.5 px within 40 px (scene_match_test,
// 256×192 px, noise 2-8 % of full scale). Two unrelated random patterns
// correlate by chance only: with 64 px tiles and σ = 1.5 px a tile holds
// about 64²/(4π·1.5²) ≈ 145 independent samples, σ ≈ 0.08 per shift, and the
// best of the 17² shifts a few σ; measured, the median tile scores 0.11-0.17
// over eight unrelated pairs. The threshold, 0.5, lies between the two with
// a wide margin on either side.
// Only the reference's registration is assumed: a pattern file not mapped
// onto the camera's pixels is "not the same scene" for this test whatever its
// Q_mod says (its Q_L, Q_C and Q_mod are still reported).
//
// The verdict, in the order tested:
//   no texture          an image's grey-level std below min_texture (of full
//                       scale): nothing to correlate, whatever Q_mod says
//                       (two constant images have Q_mod 1)
//   not the same scene  scene correlation below min_correlation
//   good / usable / poor by Q_mod (Gojani & Obayashi 2012): Pentax K-5 0.70
//                       worked, Shimadzu HPV-1 0.33 worked with more noise,
//                       Imacon DSR200 0.01 failed. The bands split the
//                       reported values near their geometric means:
//                       good ≥ 0.5, usable ≥ 0.1, poor below.

#include <atomic>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "fusion/evaluation.h"
#include "fusion/image_quality.h"

namespace bosfuse::fusion {

enum class SceneVerdict { kGood, kUsable, kPoor, kNotSameScene, kNoTexture };

// "good", "usable", "poor", "not the same scene", "no texture".
std::string to_string(SceneVerdict verdict);
// The verdict a name gives; throws std::invalid_argument on another name.
SceneVerdict scene_verdict_from_string(const std::string& name);

struct SceneMatchOptions {
  double blur_sigma_px = 1.5;    // low-pass before correlating (Gaussian σ)
  int max_shift_px = 8;          // the largest displacement a tile is searched for
  int tile_px = 64;              // side of a correlated tile (smaller on a small image)
  int max_tiles_across = 5;      // tiles spread over the image, at most this many per row and column
  double min_correlation = 0.5;  // scene correlation below this: not the same scene
  double min_texture = 0.002;    // grey-level std, of full scale (0.5 grey level at 8 bits)
  double good_q_mod = 0.5;
  double usable_q_mod = 0.1;

  std::string Validate() const;  // empty when valid
};

struct SceneMatch {
  SceneVerdict verdict = SceneVerdict::kNoTexture;
  double correlation = 0;     // median over the tiles of the best normalised correlation (0 when none was tested)
  int tiles = 0;              // tiles correlated (textured in the reference)
  QualityIndex quality;       // global Q_L, Q_C, Q_mod and the moments
  SceneMatchOptions options;  // the thresholds the verdict used
  // Colour images converted (the reference's with the first match), for
  // the caller to log: fusion/ logs nothing.
  std::vector<std::string> warnings;

  bool same_scene() const { return verdict != SceneVerdict::kNotSameScene && verdict != SceneVerdict::kNoTexture; }
  // One line: the verdict and the number that decided it against its threshold.
  std::string Describe() const;
};

class SceneMatcher {
 public:
  // Throws std::invalid_argument on invalid options or an empty reference.
  explicit SceneMatcher(const cv::Mat& reference, const SceneMatchOptions& options = {});

  // An image of another size is compared with the reference resized to it.
  SceneMatch match(const cv::Mat& image) const;

 private:
  cv::Mat reference_;
  GreyMoments reference_moments_;
  SceneMatchOptions options_;
  mutable std::atomic<bool> reference_warned_{false};  // its warnings went with a match
};

SceneMatch match_scene(const cv::Mat& image, const cv::Mat& reference, const SceneMatchOptions& options = {});

// A pair that is not the same scene (or has no texture) supports no vector:
// every vector not already masked or out of the ROI is flagged kNoPeak, and
// the summary's counts say so.
void refuse_vectors(EvaluationResult& result);

}  // namespace bosfuse::fusion
