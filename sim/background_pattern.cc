#include "sim/background_pattern.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>

#include "storage/partial_file.h"

namespace bosfuse::sim {
namespace {

constexpr double kMmPerInch = 25.4;

// Fraction of pixel (px, py) inside a disc, from 8×8 samples per pixel; exact
// 0 or 1 for pixels entirely outside or inside.
double disc_coverage(double cx, double cy, double radius, int px, int py) {
  const double nearest_x = std::clamp(cx, px - 0.5, px + 0.5), nearest_y = std::clamp(cy, py - 0.5, py + 0.5);
  if (std::hypot(nearest_x - cx, nearest_y - cy) >= radius) return 0.0;
  const double far_x = std::max(std::abs(px - 0.5 - cx), std::abs(px + 0.5 - cx));
  const double far_y = std::max(std::abs(py - 0.5 - cy), std::abs(py + 0.5 - cy));
  if (std::hypot(far_x, far_y) <= radius) return 1.0;
  constexpr int kSamples = 8;
  int inside = 0;
  for (int j = 0; j < kSamples; ++j) {
    for (int i = 0; i < kSamples; ++i) {
      const double sx = px - 0.5 + (i + 0.5) / kSamples, sy = py - 0.5 + (j + 0.5) / kSamples;
      inside += (sx - cx) * (sx - cx) + (sy - cy) * (sy - cy) < radius * radius;
    }
  }
  return double(inside) / (kSamples * kSamples);
}

std::uint32_t crc32(const unsigned char* data, std::size_t size, std::uint32_t crc = 0) {
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void put_be32(std::vector<unsigned char>& out, std::uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<unsigned char>(value >> shift));
}

std::uint32_t get_be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}

// A pHYs chunk (pixels per metre, unit 1 = metre) for `dpi`.
std::vector<unsigned char> phys_chunk(double dpi) {
  const auto per_metre = static_cast<std::uint32_t>(std::lround(dpi / kMmPerInch * 1000.0));
  std::vector<unsigned char> body{'p', 'H', 'Y', 's'};
  put_be32(body, per_metre);
  put_be32(body, per_metre);
  body.push_back(1);
  std::vector<unsigned char> chunk;
  put_be32(chunk, 9);
  chunk.insert(chunk.end(), body.begin(), body.end());
  put_be32(chunk, crc32(body.data(), body.size()));
  return chunk;
}

bool has_extension(const std::filesystem::path& path, std::initializer_list<const char*> extensions) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return std::any_of(extensions.begin(), extensions.end(), [&](const char* e) { return ext == e; });
}

}  // namespace

std::string PatternOptions::Validate() const {
  if (width_px < 1 || height_px < 1 || width_px > 60000 || height_px > 60000) {
    return fmt::format("pattern size {}x{} px is out of range (1..60000)", width_px, height_px);
  }
  if (dot_diameter_mm > 0 && !(dpi > 0)) return "a dot size in mm needs a positive dpi";
  if (!(diameter_px() >= 0.5 && diameter_px() <= 1000))
    return fmt::format("dot diameter {} px is out of range", diameter_px());
  if (!(coverage > 0 && coverage < 1))
    return fmt::format("coverage must be between 0 and 1 (exclusive), not {}", coverage);
  if (grey_levels.empty()) return "at least one dot grey level is needed";
  for (int g : grey_levels) {
    if (g < 0 || g > 255) return fmt::format("grey level {} is outside 0..255", g);
  }
  if (background_grey < 0 || background_grey > 255) return "background grey must be 0..255";
  if (!(dpi > 0)) return "dpi must be positive";
  return {};
}

double PatternOptions::diameter_px() const {
  return dot_diameter_mm > 0 ? dot_diameter_mm / kMmPerInch * dpi : dot_diameter_px;
}

BackgroundPattern generate_pattern(const PatternOptions& options) {
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  BackgroundPattern pattern;
  pattern.size = {options.width_px, options.height_px};
  pattern.dot_diameter_px = options.diameter_px();
  pattern.background_grey = options.background_grey;
  pattern.dpi = options.dpi;
  // Dots are scattered over the image grown by a diameter on each side so
  // the edges are covered as densely as the middle.
  const double margin = pattern.dot_diameter_px;
  const double area = (options.width_px + 2 * margin) * (options.height_px + 2 * margin);
  const double dot_area = std::numbers::pi * pattern.dot_diameter_px * pattern.dot_diameter_px / 4;
  const auto count = static_cast<std::size_t>(std::llround(-std::log(1 - options.coverage) * area / dot_area));
  std::mt19937_64 random(options.seed);
  std::uniform_real_distribution<double> x(-margin - 0.5, options.width_px - 0.5 + margin);
  std::uniform_real_distribution<double> y(-margin - 0.5, options.height_px - 0.5 + margin);
  std::uniform_int_distribution<std::size_t> level(0, options.grey_levels.size() - 1);
  pattern.dots.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double dot_x = x(random), dot_y = y(random);
    pattern.dots.push_back({dot_x, dot_y, options.grey_levels[level(random)]});
  }
  return pattern;
}

cv::Mat render_pattern(const BackgroundPattern& pattern) {
  cv::Mat image(pattern.size, CV_64F, cv::Scalar(pattern.background_grey));
  const double radius = pattern.dot_diameter_px / 2;
  for (const Dot& dot : pattern.dots) {
    const int x0 = std::max(0, int(std::floor(dot.x_px - radius))),
              x1 = std::min(image.cols - 1, int(std::ceil(dot.x_px + radius)));
    const int y0 = std::max(0, int(std::floor(dot.y_px - radius))),
              y1 = std::min(image.rows - 1, int(std::ceil(dot.y_px + radius)));
    for (int py = y0; py <= y1; ++py) {
      double* row = image.ptr<double>(py);
      for (int px = x0; px <= x1; ++px) {
        const double alpha = disc_coverage(dot.x_px, dot.y_px, radius, px, py);
        row[px] += alpha * (dot.grey - row[px]);
      }
    }
  }
  cv::Mat out;
  image.convertTo(out, CV_8U);
  return out;
}

void write_pattern_image(const std::filesystem::path& path, const cv::Mat& image, double dpi) {
  if (has_extension(path, {".tif", ".tiff"})) {
    const int dots = static_cast<int>(std::lround(dpi));
    const std::vector<int> params{cv::IMWRITE_TIFF_RESUNIT, 2 /* inch */, cv::IMWRITE_TIFF_XDPI, dots,
                                  cv::IMWRITE_TIFF_YDPI,    dots};
    storage::PartialFile file(path);  // keeps the extension OpenCV picks the format by
    if (!cv::imwrite(file.path().string(), image, params)) {
      throw std::runtime_error(path.string() + ": cannot write TIFF");
    }
    file.commit();
    return;
  }
  if (!has_extension(path, {".png"})) throw std::runtime_error(path.string() + ": use a .png or .tif(f) file name");
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", image, png)) throw std::runtime_error(path.string() + ": cannot encode PNG");
  // OpenCV writes no resolution: insert a pHYs chunk after IHDR (8-byte
  // signature, then IHDR of 4+4+13+4 bytes).
  constexpr std::size_t kAfterIhdr = 8 + 25;
  const auto chunk = phys_chunk(dpi);
  png.insert(png.begin() + kAfterIhdr, chunk.begin(), chunk.end());
  storage::PartialFileStream out(path);
  out.stream().write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.close();
}

double read_png_dpi(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::size_t at = 8;
  for (int chunk = 0; chunk < 64 && at + 12 <= bytes.size(); ++chunk) {
    const std::uint32_t length = get_be32(&bytes[at]);
    const std::string type(bytes.begin() + at + 4, bytes.begin() + at + 8);
    if (type == "pHYs" && length == 9 && at + 17 <= bytes.size() && bytes[at + 16] == 1) {
      return get_be32(&bytes[at + 8]) * kMmPerInch / 1000.0;
    }
    if (type == "IDAT") break;  // pHYs must come before the image data
    at += 12 + length;
  }
  return 0;
}

}  // namespace bosfuse::sim
