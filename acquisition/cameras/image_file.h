#pragma once
// Reading an image file (a camera's frame, a frame of a run, a mask) without
// trusting it. Every image bosfuse reads goes through here, which refuses
// what could cost it more than the image is worth before paying for it:
//
// 1. the file's size (stat) against the most any image within the limits
//    can need, before a byte is read;
// 2. the size its header declares, read with the format's own library
//    (libpng, libjpeg, libtiff; acquisition/cameras/image_header.h) without reading
//    the rest, against the pixel limits: a 388 KB PNG of 20000×20000 zeros
//    decodes to 400 MB per channel;
// 3. the file's size against what those pixels can need: a 256×256 PNG
//    padded to 1.9 GB (68 KB on disk when sparse) was once read whole;
// 4. once read, that the image data is all there: a truncated TIFF's strips
//    run past its end, and libjpeg reads a JPEG's whole data (OpenCV
//    decodes half a JPEG with a warning and grey for the rest);
// 5. OpenCV's decode, where running out of memory is an error naming the
//    file like every other.
//
// The limits are generous for real cameras (100 megapixels, 30000 px a
// side, 64 MB of metadata) and are changed with the environment variables
// BOSFUSE_MAX_IMAGE_PIXELS, BOSFUSE_MAX_IMAGE_SIDE_PX and
// BOSFUSE_MAX_IMAGE_METADATA_MB (docs/CONFIG.md). OpenCV's own limits
// (OPENCV_IO_MAX_IMAGE_*) cannot serve: imgcodecs reads them once, when the
// library is loaded, before any code of ours runs. Only PNG, JPEG, TIFF,
// BMP and PNM are decoded; any other format is not decoded at all (OpenCV's
// DICOM and GDAL decoders allocate before its limits are checked).

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/cameras/image_header.h"

namespace bosfuse::acquisition {

struct ImageLimits {
  std::int64_t max_pixels = 100'000'000;
  std::int64_t max_side_px = 30'000;
  // What a file may hold beyond its pixels' needs: EXIF, ICC profiles, text
  // chunks, thumbnails.
  std::int64_t max_metadata_bytes = 64'000'000;

  // The defaults, overridden by BOSFUSE_MAX_IMAGE_PIXELS,
  // BOSFUSE_MAX_IMAGE_SIDE_PX and BOSFUSE_MAX_IMAGE_METADATA_MB when set (a
  // positive integer, else an error).
  static ImageLimits from_environment();

  // The most bytes a `format` file declaring `size` may hold: twice what its
  // pixels take at the deepest pixel the format can hold (uncompressed; the
  // factor covers row padding, filter bytes and compression that expands),
  // plus max_metadata_bytes.
  std::int64_t max_file_bytes(ImageFormat format, DeclaredSize size) const;
  // The most any image within the limits may hold: max_file_bytes() of the
  // deepest format at max_pixels.
  std::int64_t max_file_bytes() const;
};

// An image file bosfuse will not decode; the message names the file and
// says why.
class ImageRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Over a limit: the pixels its header declares, or the file's size. Waiting
// does not help (a watched folder gives up on it at once).
class ImageTooLarge : public ImageRefused {
 public:
  using ImageRefused::ImageRefused;
};

// A file in one of the formats bosfuse reads that cannot be decoded:
// truncated, damaged, a header its library cannot read, no memory for it,
// or an error reading the file.
class ImageUnreadable : public ImageRefused {
 public:
  using ImageRefused::ImageRefused;
};

// The size a PNG, JPEG, TIFF, BMP or PNM header declares; nullopt for another format
// or a header its library cannot read. Decodes no pixels.
std::optional<DeclaredSize> declared_image_size(std::span<const std::uint8_t> bytes);

// cv::imdecode(IMREAD_UNCHANGED) of `bytes` once the checks above pass;
// empty when the bytes are not a PNG, JPEG, TIFF, BMP or PNM image. Throws
// ImageTooLarge or ImageUnreadable, whose messages begin with `name`.
cv::Mat decode_image(std::span<const std::uint8_t> bytes, const std::string& name,
                     const ImageLimits& limits = ImageLimits::from_environment());

// The bytes of the image file at `path`, read whole only once its size and
// header have passed the checks above (1 to 3). Empty when the file is
// missing or no regular file, or not a PNG, JPEG, TIFF, BMP or PNM image
// (then no more than its first bytes are read). Throws ImageTooLarge or
// ImageUnreadable, whose messages begin with the path.
std::vector<std::uint8_t> read_image_bytes(const std::filesystem::path& path,
                                           const ImageLimits& limits = ImageLimits::from_environment());

// decode_image() of read_image_bytes(); empty when the file is missing or
// not an image of those formats.
cv::Mat read_image_file(const std::filesystem::path& path, const ImageLimits& limits = ImageLimits::from_environment());

}  // namespace bosfuse::acquisition
