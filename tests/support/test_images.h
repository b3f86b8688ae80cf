#pragma once
// Small images for camera tests: a textured frame whose pixels identify it,
// its encoded bytes, and EXIF capture times written by exiftool (a tool
// nobody here wrote), so the reader is checked against a real writer.

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/support/subprocess.h"

namespace bosfuse::testing {

inline cv::Mat textured_frame(int seed, int depth = CV_8U, cv::Size size = {64, 48}) {
  cv::Mat image(size, depth);
  cv::RNG rng(static_cast<std::uint64_t>(seed) + 1);
  rng.fill(image, cv::RNG::UNIFORM, 0, depth == CV_16U ? 65535 : 255);
  return image;
}

inline std::vector<std::uint8_t> encoded(const cv::Mat& image, const std::string& extension) {
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(extension, image, bytes)) throw std::runtime_error("cannot encode " + extension);
  return bytes;
}

inline void write_file(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// exiftool tag arguments, e.g. {"-DateTimeOriginal=2026:11:23 10:15:30", "-SubSecTimeOriginal=250"}.
inline void write_exif(const std::filesystem::path& path, const std::vector<std::string>& tags) {
  std::string command = "exiftool -q -overwrite_original";
  for (const auto& tag : tags) command += " '" + tag + "'";
  const auto result = run_command(command + " '" + path.string() + "'");
  if (result.exit_code != 0) throw std::runtime_error("exiftool failed: " + result.output);
}

}  // namespace bosfuse::testing
