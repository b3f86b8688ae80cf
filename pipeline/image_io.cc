#include "pipeline/image_io.h"

#include "acquisition/cameras/image_file.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace bosfuse::pipeline {

cv::Mat read_image(const std::string& path, const std::string& role) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(role + " " + path + ": no such file");
  // Throws, naming the file, for an image too large, truncated or damaged.
  cv::Mat image = acquisition::read_image_file(path);
  if (image.empty())
    throw std::runtime_error(role + " " + path + ": unreadable image (not a PNG, JPEG, TIFF, BMP or PNM image bosfuse can decode)");
  return image;
}

}  // namespace bosfuse::pipeline
