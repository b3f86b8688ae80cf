#pragma once
// Image files made to hurt a reader that trusts them: a header declaring
// more pixels than the data holds, an image padded to gigabytes (sparse, so
// it costs no disk), and a TIFF whose directory comes before its pixels (as
// libtiff does not write it), so that cutting it short leaves a readable
// header with data missing.

#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

namespace bosfuse::testing {

// A decompression bomb in miniature: a valid PNG header (IHDR with a correct
// CRC) that declares `width` x `height` pixels, followed by the data of a
// 16x1 image. A reader that trusts the header allocates for the declared
// size before the data runs out.
inline std::vector<std::uint8_t> png_declaring(std::uint32_t width, std::uint32_t height) {
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", cv::Mat(1, 16, CV_8U, cv::Scalar(0)), png)) throw std::runtime_error("no PNG encoder");
  // Signature (8), IHDR length (4), "IHDR" (4), width (4), height (4), ...; the CRC covers "IHDR" and its 13 bytes.
  auto put = [&](std::size_t at, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) png[at + i] = static_cast<std::uint8_t>(value >> (24 - 8 * i));
  };
  put(16, width);
  put(20, height);
  put(29, static_cast<std::uint32_t>(crc32(0, png.data() + 12, 17)));
  return png;
}

// `bytes` at `path`, then zeros up to `size` bytes: a hole the file system
// does not store (truncate extends a file sparsely).
inline void write_padded(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes,
                         std::uint64_t size) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (::truncate(path.c_str(), static_cast<off_t>(size)) != 0)
    throw std::runtime_error("cannot extend " + path.string());
}

// An uncompressed 8-bit grey TIFF of `image` with its directory (IFD) right
// after the 8-byte header and the pixels in one strip after it.
inline std::vector<std::uint8_t> tiff_with_directory_first(const cv::Mat& image) {
  if (image.type() != CV_8UC1 || !image.isContinuous()) throw std::invalid_argument("8-bit grey, continuous");
  std::vector<std::uint8_t> tiff = {'I', 'I', 42, 0, 8, 0, 0, 0};
  auto put = [&](std::uint32_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) tiff.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  };
  const auto width = static_cast<std::uint32_t>(image.cols), height = static_cast<std::uint32_t>(image.rows);
  // (tag, type, value): type 3 is SHORT, 4 is LONG; one value each, in ascending tag order.
  const std::uint32_t entries[][3] = {{256, 4, width}, {257, 4, height}, {258, 3, 8},
                                      {259, 3, 1},     {262, 3, 1},      {273, 4, 0},
                                      {277, 3, 1},     {278, 4, height}, {279, 4, width * height}};
  const std::uint32_t count = sizeof entries / sizeof entries[0];
  const std::uint32_t data_at = 8 + 2 + count * 12 + 4;
  put(count, 2);
  for (const auto& e : entries) {
    put(e[0], 2);
    put(e[1], 2);
    put(1, 4);
    put(e[0] == 273 ? data_at : e[2], 4);  // a SHORT sits in the first two bytes of the value, little-endian
  }
  put(0, 4);  // no next directory
  tiff.insert(tiff.end(), image.data, image.data + image.total());
  return tiff;
}

}  // namespace bosfuse::testing
