#include "fusion/scene_match.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <vector>

#include "fusion/image_input.h"

namespace bosfuse::fusion {
namespace {

// Where the tiles go on an image of `size`: the shift searched and the tile
// side shrink on a small image so that one tile and its search fit.
struct TileLayout {
  int shift = 0;
  int tile = 0;
  std::vector<int> xs, ys;
};

std::vector<int> spread(int length, int shift, int tile, int most) {
  const int room = length - 2 * shift - tile;  // the last tile's origin, minus the first's
  const int count = std::clamp((room + tile - 1) / tile + 1, 1, most);
  std::vector<int> origins;
  for (int i = 0; i < count; ++i) origins.push_back(shift + (count > 1 ? room * i / (count - 1) : room / 2));
  return origins;
}

TileLayout tile_layout(cv::Size size, const SceneMatchOptions& o) {
  const int smaller = std::min(size.width, size.height);
  TileLayout layout;
  layout.shift = std::clamp((smaller - 8) / 4, 0, o.max_shift_px);
  layout.tile = std::min(o.tile_px, smaller - 2 * layout.shift);
  if (layout.tile < 4) return layout;  // too small an image to correlate: no tiles
  layout.xs = spread(size.width, layout.shift, layout.tile, o.max_tiles_across);
  layout.ys = spread(size.height, layout.shift, layout.tile, o.max_tiles_across);
  return layout;
}

// A region of an image as grey float of full scale 1, low-pass filtered.
// The blur reads a margin beyond the region where the image has one.
cv::Mat blurred_region(const cv::Mat& image, cv::Rect region, double sigma_px) {
  const int margin = static_cast<int>(std::ceil(3 * sigma_px));
  const cv::Rect padded =
      (region + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) & cv::Rect(0, 0, image.cols, image.rows);
  cv::Mat grey = to_grey_unit_float(image(padded), "image");
  if (sigma_px > 0) cv::GaussianBlur(grey, grey, cv::Size(), sigma_px, sigma_px, cv::BORDER_REFLECT);
  return grey(region - padded.tl()).clone();
}

bool has_spread(const cv::Mat& grey) {
  cv::Scalar mean, std_dev;
  cv::meanStdDev(grey, mean, std_dev);
  return std_dev[0] > 1e-6;
}

// The best normalised correlation of a reference tile with the image over
// the shifts of the layout; nullopt when the reference tile is flat.
std::optional<double> tile_correlation(const cv::Mat& image, const cv::Mat& reference, cv::Point origin,
                                       const TileLayout& layout, double sigma_px) {
  const cv::Rect tile(origin, cv::Size(layout.tile, layout.tile));
  const cv::Mat templ = blurred_region(reference, tile, sigma_px);
  if (!has_spread(templ)) return std::nullopt;
  const cv::Rect search = tile + cv::Size(2 * layout.shift, 2 * layout.shift) - cv::Point(layout.shift, layout.shift);
  const cv::Mat around = blurred_region(image, search, sigma_px);
  if (!has_spread(around)) return 0.0;
  cv::Mat scores;
  cv::matchTemplate(around, templ, scores, cv::TM_CCOEFF_NORMED);
  double best = 0;
  cv::minMaxLoc(scores, nullptr, &best);
  return std::isfinite(best) ? best : 0.0;
}

double median(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), middle, values.end());
  if (values.size() % 2 == 1) return *middle;
  return 0.5 * (*middle + *std::max_element(values.begin(), middle));
}

SceneVerdict verdict_of(const SceneMatch& m) {
  const auto& o = m.options;
  if (m.quality.std_image < o.min_texture || m.quality.std_reference < o.min_texture) return SceneVerdict::kNoTexture;
  if (m.tiles == 0 || m.correlation < o.min_correlation) return SceneVerdict::kNotSameScene;
  if (m.quality.q_mod >= o.good_q_mod) return SceneVerdict::kGood;
  if (m.quality.q_mod >= o.usable_q_mod) return SceneVerdict::kUsable;
  return SceneVerdict::kPoor;
}

}  // namespace

std::string to_string(SceneVerdict verdict) {
  switch (verdict) {
    case SceneVerdict::kGood:
      return "good";
    case SceneVerdict::kUsable:
      return "usable";
    case SceneVerdict::kPoor:
      return "poor";
    case SceneVerdict::kNotSameScene:
      return "not the same scene";
    case SceneVerdict::kNoTexture:
      return "no texture";
  }
  return "unknown";
}

SceneVerdict scene_verdict_from_string(const std::string& name) {
  for (const auto v : {SceneVerdict::kGood, SceneVerdict::kUsable, SceneVerdict::kPoor, SceneVerdict::kNotSameScene,
                       SceneVerdict::kNoTexture}) {
    if (to_string(v) == name) return v;
  }
  throw std::invalid_argument("'" + name + "' is not a scene verdict");
}

std::string SceneMatchOptions::Validate() const {
  if (!(blur_sigma_px >= 0 && blur_sigma_px <= 16))
    return fmt::format("scene blur σ {} px is not 0 to 16", blur_sigma_px);
  if (max_shift_px < 0 || max_shift_px > 64) return fmt::format("scene search ±{} px is not 0 to 64", max_shift_px);
  if (tile_px < 8 || tile_px > 512) return fmt::format("scene tile {} px is not 8 to 512", tile_px);
  if (max_tiles_across < 1 || max_tiles_across > 64)
    return fmt::format("{} tiles across is not 1 to 64", max_tiles_across);
  if (!(min_correlation > -1 && min_correlation < 1))
    return fmt::format("scene correlation threshold {} is not in (-1, 1)", min_correlation);
  if (!(min_texture >= 0 && min_texture < 1)) return fmt::format("texture threshold {} is not in [0, 1)", min_texture);
  if (!(usable_q_mod >= 0 && usable_q_mod <= good_q_mod && good_q_mod <= 1)) {
    return fmt::format("Q_mod bands need 0 ≤ usable ({}) ≤ good ({}) ≤ 1", usable_q_mod, good_q_mod);
  }
  return {};
}

std::string SceneMatch::Describe() const {
  const auto& o = options;
  switch (verdict) {
    case SceneVerdict::kNoTexture:
      return fmt::format(
          "no texture (grey-level std {:.4f} in the image, {:.4f} in the reference, of full scale; "
          "texture needs ≥ {:.4f})",
          quality.std_image, quality.std_reference, o.min_texture);
    case SceneVerdict::kNotSameScene:
      return fmt::format(
          "not the same scene (scene correlation {:.3f} < {:.2f}: median of {} tiles, blurred σ {} px, "
          "best within ±{} px)",
          correlation, o.min_correlation, tiles, o.blur_sigma_px, o.max_shift_px);
    default:
      return fmt::format("{} (Q_mod {:.3f}; good ≥ {:.2f}, usable ≥ {:.2f}; scene correlation {:.3f} ≥ {:.2f})",
                         to_string(verdict), quality.q_mod, o.good_q_mod, o.usable_q_mod, correlation,
                         o.min_correlation);
  }
}

SceneMatcher::SceneMatcher(const cv::Mat& reference, const SceneMatchOptions& options)
    : reference_(reference), reference_moments_(grey_moments(reference, "reference")), options_(options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
}

SceneMatch SceneMatcher::match(const cv::Mat& image) const {
  SceneMatch out;
  out.options = options_;
  if (!reference_warned_.exchange(true)) out.warnings = reference_moments_.warnings;
  const GreyMoments image_moments = grey_moments(image, "image");
  out.warnings.insert(out.warnings.end(), image_moments.warnings.begin(), image_moments.warnings.end());
  out.quality = modified_quality_index(image_moments, reference_moments_);
  cv::Mat reference = reference_;
  if (reference.size() != image.size()) cv::resize(reference_, reference, image.size(), 0, 0, cv::INTER_AREA);
  const TileLayout layout = tile_layout(image.size(), options_);
  std::vector<double> scores;
  for (const int y : layout.ys) {
    for (const int x : layout.xs) {
      if (const auto score = tile_correlation(image, reference, {x, y}, layout, options_.blur_sigma_px)) {
        scores.push_back(*score);
      }
    }
  }
  out.tiles = static_cast<int>(scores.size());
  out.correlation = median(scores);
  out.verdict = verdict_of(out);
  return out;
}

SceneMatch match_scene(const cv::Mat& image, const cv::Mat& reference, const SceneMatchOptions& options) {
  return SceneMatcher(reference, options).match(image);
}

void refuse_vectors(EvaluationResult& result) {
  for (auto& v : result.field.vectors) {
    if (v.flag == VectorFlag::kOk || v.flag == VectorFlag::kOutlierReplaced) v.flag = VectorFlag::kNoPeak;
  }
  result.summary.valid = 0;
  result.summary.outliers_replaced = 0;
  result.summary.no_peak = result.field.count(VectorFlag::kNoPeak);
}

}  // namespace bosfuse::fusion
