#include "fusion/image_quality.h"

#include <fmt/format.h>

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

GreyMoments grey_moments(const cv::Mat& image, const std::string& name) {
  if (image.empty()) throw std::invalid_argument(name + ": the image is empty (unreadable file or no pixels)");
  GreyMoments moments;
  cv::Mat grey = image;
  double scale = full_scale(image.depth());
  if (image.depth() == CV_32F || image.depth() == CV_64F) {
    grey = to_grey_unit_float(image, name, &moments.warnings);  // NaNs patched, colour converted
    scale = 1.0;
  } else if (image.channels() == 3 || image.channels() == 4) {
    moments.warnings.push_back(colour_conversion_warning(name, image.channels()));
    cv::cvtColor(image, grey, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  } else if (image.channels() != 1) {
    throw std::invalid_argument(fmt::format("{}: {} channels, expected grey or colour", name, image.channels()));
  }
  cv::Scalar mean, std_dev;
  cv::meanStdDev(grey, mean, std_dev);  // population σ, accumulated in double
  const double n = double(grey.total());
  moments.mean = mean[0] / scale;
  moments.std = n > 1 ? std_dev[0] / scale * std::sqrt(n / (n - 1)) : 0.0;
  return moments;
}

QualityIndex modified_quality_index(const GreyMoments& image, const GreyMoments& reference) {
  QualityIndex q;
  q.mean_image = image.mean;
  q.mean_reference = reference.mean;
  q.std_image = image.std;
  q.std_reference = reference.std;
  q.q_l = similarity(q.mean_image, q.mean_reference);
  q.q_c = similarity(q.std_image, q.std_reference);
  q.q_mod = q.q_l * q.q_c;
  return q;
}

QualityIndex modified_quality_index(const cv::Mat& image, const cv::Mat& reference) {
  return modified_quality_index(grey_moments(image, "image"), grey_moments(reference, "reference"));
}

QualityReport assess_quality(const cv::Mat& image, const cv::Mat& reference, const QualityOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  QualityReport report;
  const GreyMoments image_moments = grey_moments(image, "image");
  const GreyMoments reference_moments = grey_moments(reference, "reference");
  report.global = modified_quality_index(image_moments, reference_moments);
  for (const GreyMoments* m : {&image_moments, &reference_moments}) {
    report.warnings.insert(report.warnings.end(), m->warnings.begin(), m->warnings.end());
  }
  const cv::Mat x = to_grey_unit_float(image, "image", &report.warnings);
  cv::Mat y = to_grey_unit_float(reference, "reference", &report.warnings);
  if (y.size() != x.size()) {
    report.warnings.push_back(fmt::format("reference {}x{} resized to the image's {}x{} for the sliding-window indices",
                                          y.cols, y.rows, x.cols, x.rows));
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
