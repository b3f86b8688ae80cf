#include "fusion/image_input.h"

#include <fmt/format.h>
#include <sys/mman.h>

#include <cstdint>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace bosfuse::fusion {
namespace {

std::string describe(cv::Size size) { return fmt::format("{}x{}", size.width, size.height); }

}  // namespace

std::string colour_conversion_warning(const std::string& name, int channels) {
  return fmt::format("{}: colour image ({} channels) converted to grey", name, channels);
}

double full_scale(int depth) {
  switch (depth) {
    case CV_8U:
      return 255.0;
    case CV_8S:
      return 127.0;
    case CV_16U:
      return 65535.0;
    case CV_16S:
      return 32767.0;
    default:
      return 1.0;  // float images are taken as scaled already
  }
}

cv::Mat to_grey_unit_float(const cv::Mat& image, const std::string& name, std::vector<std::string>* warnings) {
  cv::Mat unit;
  to_grey_unit_float(image, name, warnings, unit);
  return unit;
}

void create_large_image(cv::Mat& image, int rows, int cols, int type) {
  constexpr std::uintptr_t kHugePage = 2u << 20;
  if (image.rows == rows && image.cols == cols && image.type() == type) return;
  image.create(rows, cols, type);
  // Untouched yet (fresh from mmap at this size): only the whole 2 MB pages
  // inside the buffer can be huge.
  const auto begin = reinterpret_cast<std::uintptr_t>(image.datastart);
  const auto end = reinterpret_cast<std::uintptr_t>(image.dataend);
  const std::uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1), last = end & ~(kHugePage - 1);
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
}

void to_grey_unit_float(const cv::Mat& image, const std::string& name, std::vector<std::string>* warnings,
                        cv::Mat& out) {
  if (image.empty()) throw std::invalid_argument(name + ": the image is empty (unreadable file or no pixels)");
  cv::Mat grey = image;
  if (image.channels() == 3 || image.channels() == 4) {
    if (warnings) warnings->push_back(colour_conversion_warning(name, image.channels()));
    cv::cvtColor(image, grey, image.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  } else if (image.channels() != 1) {
    throw std::invalid_argument(fmt::format("{}: {} channels, expected grey or colour", name, image.channels()));
  }
  CV_Assert(out.empty() || out.data != grey.data);
  create_large_image(out, grey.rows, grey.cols, CV_32F);
  // In bands of rows on all cores: OpenCV converts on one thread, and a
  // 16 MP frame's conversion left the other core idle for ~15 ms a frame.
  // A probe's crop costs less than waking another thread.
  const double scale = 1.0 / full_scale(grey.depth());
  const auto convert_rows = [&](const cv::Range& rows) {
    cv::Mat band = out.rowRange(rows.start, rows.end);
    grey.rowRange(rows.start, rows.end).convertTo(band, CV_32F, scale);
  };
  if (grey.total() < (1u << 16)) {
    convert_rows(cv::Range(0, grey.rows));
  } else {
    cv::parallel_for_(cv::Range(0, grey.rows), convert_rows);
  }
  // Non-finite pixels in a float input would poison every sum they enter;
  // integer input cannot hold them, and the test is a whole pass over the
  // image.
  const int depth = grey.depth();
  if (depth == CV_32F || depth == CV_64F || depth == CV_16F) cv::patchNaNs(out, 0.0);
}

void check_image_pair(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask) {
  if (reference.empty()) throw std::invalid_argument("reference image is empty (unreadable file or no pixels)");
  if (measurement.empty()) throw std::invalid_argument("measurement image is empty (unreadable file or no pixels)");
  if (reference.size() != measurement.size()) {
    throw std::invalid_argument(fmt::format("image sizes differ: reference {} but measurement {}",
                                            describe(reference.size()), describe(measurement.size())));
  }
  if (!mask.empty() && mask.size() != reference.size()) {
    throw std::invalid_argument(
        fmt::format("mask size {} differs from the image size {}", describe(mask.size()), describe(reference.size())));
  }
}

void check_window_fits(int window_px, cv::Size image_size) {
  if (window_px > image_size.width || window_px > image_size.height) {
    throw std::invalid_argument(
        fmt::format("interrogation window {} px is larger than the image ({})", window_px, describe(image_size)));
  }
}

cv::Mat to_exclusion_mask(const cv::Mat& mask) {
  if (mask.empty()) return {};
  cv::Mat grey = mask;
  if (mask.channels() > 1) cv::cvtColor(mask, grey, mask.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  cv::Mat excluded;
  cv::compare(grey, 0, excluded, cv::CMP_NE);
  return excluded;
}

}  // namespace bosfuse::fusion
