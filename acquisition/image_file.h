#pragma once
// Reading an image file (a camera's frame, a frame of a run, a mask) without
// trusting it. A small file may declare a huge image: a 388 KB PNG of
// 20000×20000 zeros decodes to 400 MB per channel. Every image bosfuse reads
// goes through here, which reads the declared size from the file's header
// with the format's own library (libpng, libjpeg, libtiff) and refuses an
// image over the limits before anything is decoded or allocated.
//
// The limits are generous for real cameras (100 megapixels, 30000 px a
// side) and are changed with the environment variables
// BOSFUSE_MAX_IMAGE_PIXELS and BOSFUSE_MAX_IMAGE_SIDE_PX (docs/CONFIG.md).
// OpenCV's own limits (OPENCV_IO_MAX_IMAGE_*) cannot serve: imgcodecs reads
// them once, when the library is loaded, before any code of ours runs.
// BMP and PNM are decoded under OpenCV's limits only (2^30 pixels); any
// other format is not decoded at all (OpenCV's DICOM and GDAL decoders
// allocate before its limits are checked).

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

namespace bosfuse::acquisition {

struct ImageLimits {
  std::int64_t max_pixels = 100'000'000;
  std::int64_t max_side_px = 30'000;

  // The defaults, overridden by BOSFUSE_MAX_IMAGE_PIXELS and
  // BOSFUSE_MAX_IMAGE_SIDE_PX when set (a positive integer, else an error).
  static ImageLimits from_environment();
};

// An image whose header declares more than the limits allow.
class ImageTooLarge : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a header declares: 64-bit, since a TIFF may declare 2^32 - 1 a side.
struct DeclaredSize {
  std::int64_t width_px = 0;
  std::int64_t height_px = 0;
};

// The size a PNG, JPEG, TIFF, BMP or PNM header declares; nullopt for another format
// or a header its library cannot read. Decodes no pixels.
std::optional<DeclaredSize> declared_image_size(std::span<const std::uint8_t> bytes);

// cv::imdecode(IMREAD_UNCHANGED) of `bytes` once the declared size is within
// `limits`; empty when the bytes are not a PNG, JPEG, TIFF, BMP or PNM image
// OpenCV can decode. Throws
// ImageTooLarge naming `name` and the declared size.
cv::Mat decode_image(std::span<const std::uint8_t> bytes, const std::string& name,
                     const ImageLimits& limits = ImageLimits::from_environment());

// decode_image() of a file's bytes; empty when it is missing or unreadable.
cv::Mat read_image_file(const std::filesystem::path& path, const ImageLimits& limits = ImageLimits::from_environment());

}  // namespace bosfuse::acquisition
