#include "fusion/evaluation.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>

namespace bosfuse::fusion {

namespace {

std::string search_description(const EvaluationSummary& s) {
  if (s.first_window_px == 0) return {};
  const char* how = s.search_beyond_reach ? ", widest the scene allows"
                    : s.search_widened    ? ", widened from the scene"
                    : s.search_from_scene ? ", the scene needs no more"
                                          : ", as given";
  return fmt::format("; search ±{:g} px from {} px windows{}{}, {} of {} first-pass windows on the bound",
                     s.max_shift_px, s.first_window_px, how, s.search_stored ? " (stored)" : "", s.first_pass_on_bound,
                     s.first_pass_windows);
}

}  // namespace

std::string EvaluationSummary::BriefReport() const {
  const std::string windows = fmt::format("{}", fmt::join(window_px_per_pass, ","));
  return fmt::format(
      "{}: {} vectors, {} valid, {} outliers replaced, {} no texture, {} masked, {} out of ROI, {} no peak, "
      "{} beyond search; {} pass(es) (windows {} px){}{}{}; {:.3f} s",
      method, vectors, valid, outliers_replaced, no_texture, masked, out_of_roi, no_peak, beyond_search, passes_run,
      windows, converged ? ", converged" : "",
      passes_run > 1 && refined_fraction < 1 ? fmt::format(", {:.1f} % refined", 100 * refined_fraction) : "",
      search_description(*this), seconds);
}

double EvaluationSummary::on_bound_fraction() const {
  return first_pass_windows > 0 ? double(first_pass_on_bound) / first_pass_windows : 0.0;
}

std::string search_bound_warning(const EvaluationSummary& s) {
  if (s.search_beyond_reach) {
    return fmt::format(
        "most sampled windows showed no clear correlation peak even with the widest search the scene allows (±{:g} "
        "px, {} px first windows); {} of {} windows ({:.1f} %) peaked on the bound and are flagged beyond-search, "
        "windows without a clear peak no-peak. The displacements may exceed that search (evaluate with a larger "
        "ROI), the images may not show the same background, or light that does not move with the pattern may "
        "dominate the correlation (try --preprocess highpass)",
        s.max_shift_px, s.first_window_px, s.first_pass_on_bound, s.first_pass_windows, 100 * s.on_bound_fraction());
  }
  if (s.on_bound_fraction() <= kOnBoundWarningFraction) return {};
  return fmt::format(
      "{} of {} windows ({:.1f} %) peaked on the ±{:g} px search bound and are flagged beyond-search: raise "
      "--max-shift or leave it unset to let the scene set it",
      s.first_pass_on_bound, s.first_pass_windows, 100 * s.on_bound_fraction(), s.max_shift_px);
}

cv::Rect effective_roi(cv::Rect roi, cv::Size image_size) {
  if (roi.width == 0 || roi.height == 0) return {cv::Point(0, 0), image_size};
  const std::string described = fmt::format("region of interest {},{},{},{}", roi.x, roi.y, roi.width, roi.height);
  if (roi.width < 0 || roi.height < 0) throw std::invalid_argument(described + " has a negative size");
  // 64-bit: x + width of a user's ROI need not fit an int (cv::Rect::area and
  // operator& would overflow).
  const std::int64_t x0 = std::max<std::int64_t>(roi.x, 0), y0 = std::max<std::int64_t>(roi.y, 0);
  const std::int64_t x1 = std::min<std::int64_t>(std::int64_t{roi.x} + roi.width, image_size.width);
  const std::int64_t y1 = std::min<std::int64_t>(std::int64_t{roi.y} + roi.height, image_size.height);
  if (x1 <= x0 || y1 <= y0) {
    throw std::invalid_argument(
        fmt::format("{} lies outside the {}x{} image", described, image_size.width, image_size.height));
  }
  return {static_cast<int>(x0), static_cast<int>(y0), static_cast<int>(x1 - x0), static_cast<int>(y1 - y0)};
}

GridGeometry evaluation_grid(cv::Rect roi, int window_px, int step_px) {
  GridGeometry grid;
  grid.step_px = step_px;
  grid.x0_px = roi.x + (window_px - 1) / 2.0;
  grid.y0_px = roi.y + (window_px - 1) / 2.0;
  grid.cols = roi.width >= window_px ? (roi.width - window_px) / step_px + 1 : 0;
  grid.rows = roi.height >= window_px ? (roi.height - window_px) / step_px + 1 : 0;
  return grid;
}

DisplacementField field_on_grid(const GridGeometry& grid) {
  DisplacementField field;
  field.rows = grid.rows;
  field.cols = grid.cols;
  field.vectors.resize(static_cast<std::size_t>(grid.rows) * grid.cols);
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      auto& v = field.at(r, c);
      v.x_px = grid.x0_px + c * grid.step_px;
      v.y_px = grid.y0_px + r * grid.step_px;
    }
  }
  return field;
}

void count_flags(const DisplacementField& field, EvaluationSummary& summary) {
  // One pass over the field (250,000 vectors for 16 MP), not one per flag.
  std::array<std::size_t, 256> counts{};
  for (const auto& v : field.vectors) ++counts[static_cast<std::uint8_t>(v.flag)];
  const auto count = [&](VectorFlag flag) { return counts[static_cast<std::uint8_t>(flag)]; };
  summary.vectors = field.size();
  summary.valid = count(VectorFlag::kOk);
  summary.outliers_replaced = count(VectorFlag::kOutlierReplaced);
  summary.no_texture = count(VectorFlag::kNoTexture);
  summary.masked = count(VectorFlag::kMasked);
  summary.out_of_roi = count(VectorFlag::kOutOfRoi);
  summary.no_peak = count(VectorFlag::kNoPeak);
  summary.beyond_search = count(VectorFlag::kBeyondSearch);
}

}  // namespace bosfuse::fusion
