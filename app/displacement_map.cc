#include "app/displacement_map.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace bosfuse::app {
namespace {

constexpr int kBarWidth = 90;

cv::Mat colour(const cv::Mat& values, double low, double high) {
  cv::Mat scaled;
  values.convertTo(scaled, CV_8U, 255.0 / std::max(high - low, 1e-12), -low * 255.0 / std::max(high - low, 1e-12));
  cv::Mat coloured;
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_JET);
  return coloured;
}

cv::Mat with_colour_bar(const cv::Mat& map, double low, double high, const char* label) {
  cv::Mat out(map.rows, map.cols + kBarWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  map.copyTo(out(cv::Rect(0, 0, map.cols, map.rows)));
  const int top = 20, bottom = map.rows - 20, height = std::max(bottom - top, 2);
  cv::Mat ramp(height, 1, CV_64F);
  for (int i = 0; i < height; ++i) ramp.at<double>(i) = high - (high - low) * i / (height - 1);
  cv::Mat bar;
  cv::resize(colour(ramp, low, high), bar, cv::Size(16, height), 0, 0, cv::INTER_NEAREST);
  bar.copyTo(out(cv::Rect(map.cols + 8, top, 16, height)));
  for (int tick = 0; tick <= 4; ++tick) {
    const int y = top + (height - 1) * tick / 4;
    const double value = high - (high - low) * tick / 4;
    cv::putText(out, fmt::format("{:.3g}", value), {map.cols + 28, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  cv::putText(out, label, {map.cols + 4, 14}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  return out;
}

void draw_contours(cv::Mat& map, const cv::Mat& magnitude, double spacing, double high) {
  if (!(spacing > 0)) return;
  const int levels = std::min(200, static_cast<int>(high / spacing));
  for (int k = 1; k <= levels; ++k) {
    cv::Mat above = magnitude >= k * spacing;
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(above, contours, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(map, contours, -1, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
}

// Gives nodes without a measurement the mean of their filled neighbours, so
// that interpolating the map does not draw false rings around a mask.
void fill_gaps(cv::Mat& magnitude, cv::Mat filled) {
  for (int sweep = 0; sweep < 64 && cv::countNonZero(filled) < static_cast<int>(filled.total()); ++sweep) {
    const cv::Mat before = filled.clone();
    for (int r = 0; r < magnitude.rows; ++r) {
      for (int c = 0; c < magnitude.cols; ++c) {
        if (before.at<std::uint8_t>(r, c)) continue;
        double sum = 0;
        int count = 0;
        for (int dr = -1; dr <= 1; ++dr) {
          for (int dc = -1; dc <= 1; ++dc) {
            const int rr = r + dr, cc = c + dc;
            if (rr < 0 || cc < 0 || rr >= magnitude.rows || cc >= magnitude.cols || !before.at<std::uint8_t>(rr, cc)) {
              continue;
            }
            sum += magnitude.at<float>(rr, cc);
            ++count;
          }
        }
        if (count == 0) continue;
        magnitude.at<float>(r, c) = static_cast<float>(sum / count);
        filled.at<std::uint8_t>(r, c) = 255;
      }
    }
  }
}

}  // namespace

cv::Mat draw_displacement_map(const fusion::DisplacementField& field, const MapOptions& options) {
  if (field.rows == 0 || field.cols == 0) throw std::runtime_error("no vectors to draw");
  cv::Mat magnitude(field.rows, field.cols, CV_32F), invalid(field.rows, field.cols, CV_8U);
  double high = 0;
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) {
      const auto& v = field.at(r, c);
      const bool shown = v.valid() || v.flag == fusion::VectorFlag::kOutlierReplaced;
      magnitude.at<float>(r, c) = shown ? static_cast<float>(std::hypot(v.u_px, v.v_px)) : 0.f;
      invalid.at<std::uint8_t>(r, c) = shown ? 0 : 255;
      if (shown) high = std::max(high, double(magnitude.at<float>(r, c)));
    }
  }
  if (high <= 0) high = 1;
  cv::Mat shown = 255 - invalid;
  fill_gaps(magnitude, shown);
  const double scale = std::max(1.0, double(options.target_width_px) / field.cols);
  const cv::Size size(static_cast<int>(field.cols * scale), static_cast<int>(field.rows * scale));
  cv::Mat fine, fine_invalid;
  cv::resize(magnitude, fine, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(invalid, fine_invalid, size, 0, 0, cv::INTER_NEAREST);
  cv::Mat map = colour(fine, 0, high);
  draw_contours(map, fine, options.contour_spacing_px, high);
  map.setTo(cv::Scalar(160, 160, 160), fine_invalid);
  return with_colour_bar(map, 0, high, "|shift| px");
}

cv::Mat draw_scalar_map(const cv::Mat& values, double low, double high, const char* label) {
  cv::Mat map = colour(values, low, high);
  if (map.cols < 400) cv::resize(map, map, cv::Size(), 400.0 / map.cols, 400.0 / map.cols, cv::INTER_NEAREST);
  return with_colour_bar(map, low, high, label);
}

}  // namespace bosfuse::app
