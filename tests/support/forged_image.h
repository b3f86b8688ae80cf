#pragma once
// A decompression bomb in miniature: a valid PNG header (IHDR with a correct
// CRC) that declares `width` x `height` pixels, followed by the data of a
// 16x1 image. A reader that trusts the header allocates for the declared
// size before the data runs out.

#include <zlib.h>

#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

namespace bosfuse::testing {

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

}  // namespace bosfuse::testing
