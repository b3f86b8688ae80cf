#include "fusion/image_quality.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fusion/image_input.h"

namespace bosfuse::fusion {
namespace {

// 2ab/(a² + b²), defined as 1 when both are 0.
double similarity(double a, double b) {
  const double denominator = a * a + b * b;
  return denominator > 1e-30 ? 2 * a * b / denominator : 1.0;
}

struct Moments {
  double mean_x, mean_y, var_x, var_y, cov;
};

// The Wang–Bovik correlation term, defined for flat windows.
double correlation(const Moments& m) {
  const double product = m.var_x * m.var_y;
  if (m.var_x < 1e-30 && m.var_y < 1e-30) return 1.0;
  if (product < 1e-60) return 0.0;
  return m.cov / std::sqrt(product);
}

double box(const cv::Mat& s, int x, int y, int w) {
  return s.at<double>(y + w, x + w) - s.at<double>(y, x + w) - s.at<double>(y + w, x) + s.at<double>(y, x);
}

}  // namespace

std::string QualityOptions::Validate() const {
  if (window_px < 2 || window_px > 512) return fmt::format("quality window must be 2 to 512 px, not {}", window_px);
  return {};
}

QualityIndex modified_quality_index(const cv::Mat& image, const cv::Mat& reference) {
  const cv::Mat x = to_grey_unit_float(image, "image");
  const cv::Mat y = to_grey_unit_float(reference, "reference");
  cv::Scalar mean_x, std_x, mean_y, std_y;
  cv::meanStdDev(x, mean_x, std_x);  // population σ, accumulated in double
  cv::meanStdDev(y, mean_y, std_y);
  const double nx = double(x.total()), ny = double(y.total());
  QualityIndex q;
  q.mean_image = mean_x[0];
  q.mean_reference = mean_y[0];
  q.std_image = nx > 1 ? std_x[0] * std::sqrt(nx / (nx - 1)) : 0.0;
  q.std_reference = ny > 1 ? std_y[0] * std::sqrt(ny / (ny - 1)) : 0.0;
  q.q_l = similarity(q.mean_image, q.mean_reference);
  q.q_c = similarity(q.std_image, q.std_reference);
  q.q_mod = q.q_l * q.q_c;
  return q;
}

QualityReport assess_quality(const cv::Mat& image, const cv::Mat& reference, const QualityOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  QualityReport report;
  report.global = modified_quality_index(image, reference);
  const cv::Mat x = to_grey_unit_float(image, "image");
  cv::Mat y = to_grey_unit_float(reference, "reference");
  if (y.size() != x.size()) {
    spdlog::warn("reference {}x{} resized to the image's {}x{} for the sliding-window indices", y.cols, y.rows, x.cols,
                 x.rows);
    cv::resize(y, y, x.size(), 0, 0, cv::INTER_AREA);
  }
  const int w = options.window_px;
  check_window_fits(w, x.size());
  cv::Mat sx, sxx, sy, syy, sxy;
  cv::integral(x, sx, sxx, CV_64F, CV_64F);
  cv::integral(y, sy, syy, CV_64F, CV_64F);
  cv::Mat xy;
  cv::multiply(x, y, xy, 1.0, CV_64F);
  cv::integral(xy, sxy, CV_64F);
  const double n = double(w) * w;
  report.local_q_mod.create(x.rows - w + 1, x.cols - w + 1, CV_64F);
  double sum_q = 0, sum_q_mod = 0;
  for (int r = 0; r < report.local_q_mod.rows; ++r) {
    for (int c = 0; c < report.local_q_mod.cols; ++c) {
      Moments m;
      m.mean_x = box(sx, c, r, w) / n;
      m.mean_y = box(sy, c, r, w) / n;
      // Sample (co)variances; clamp the rounding noise of flat windows.
      m.var_x = std::max(0.0, (box(sxx, c, r, w) - n * m.mean_x * m.mean_x) / (n - 1));
      m.var_y = std::max(0.0, (box(syy, c, r, w) - n * m.mean_y * m.mean_y) / (n - 1));
      m.cov = (box(sxy, c, r, w) - n * m.mean_x * m.mean_y) / (n - 1);
      const double q_mod = similarity(m.mean_x, m.mean_y) * similarity(std::sqrt(m.var_x), std::sqrt(m.var_y));
      report.local_q_mod.at<double>(r, c) = q_mod;
      sum_q_mod += q_mod;
      sum_q += correlation(m) * q_mod;
    }
  }
  const double windows = double(report.local_q_mod.total());
  report.universal_index = sum_q / windows;
  report.mean_local_q_mod = sum_q_mod / windows;
  return report;
}

}  // namespace bosfuse::fusion
