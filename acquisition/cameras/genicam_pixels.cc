#include "acquisition/cameras/genicam_pixels.h"

#include <stdexcept>
#include <vector>

namespace bosfuse::acquisition {
namespace {

// GigE Vision Mono10Packed / Mono12Packed: bytes B0 B1 B2 hold pixels p0,
// p1; B0 and B2 are their high 8 bits, B1 their low bits (p0 in the low
// nibble, p1 in the high).
void unpack_gvsp_pairs(const std::uint8_t* in, std::uint16_t* out, std::size_t pixels, int bits) {
  const int low_bits = bits - 8;
  const std::uint8_t mask = static_cast<std::uint8_t>((1 << low_bits) - 1);
  for (std::size_t i = 0; i < pixels; i += 2) {
    const std::uint8_t* b = in + (i / 2) * 3;
    out[i] = static_cast<std::uint16_t>((b[0] << low_bits) | (b[1] & mask));
    if (i + 1 < pixels) out[i + 1] = static_cast<std::uint16_t>((b[2] << low_bits) | ((b[1] >> 4) & mask));
  }
}

// PFNC Mono10p / Mono12p: a little-endian bit stream, pixel i in bits
// [i·bits, (i+1)·bits).
void unpack_lsb_stream(const std::uint8_t* in, std::uint16_t* out, std::size_t pixels, int bits) {
  const std::uint32_t mask = (1u << bits) - 1;
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::size_t bit = i * static_cast<std::size_t>(bits);
    const std::size_t byte = bit / 8;
    std::uint32_t word = in[byte] | (static_cast<std::uint32_t>(in[byte + 1]) << 8);
    if ((bit % 8) + bits > 16) word |= static_cast<std::uint32_t>(in[byte + 2]) << 16;
    out[i] = static_cast<std::uint16_t>((word >> (bit % 8)) & mask);
  }
}

std::size_t genicam_packed_bytes(std::size_t pixels, int bits, bool gvsp) {
  return gvsp ? (pixels + 1) / 2 * 3 : (pixels * static_cast<std::size_t>(bits) + 7) / 8;
}

}  // namespace

cv::Mat genicam_pixels_to_image(const std::string& pixel_format, const std::uint8_t* data, std::size_t size,
                                int width_px, int height_px) {
  if (width_px < 1 || height_px < 1)
    throw std::invalid_argument("frame of " + std::to_string(width_px) + "×" + std::to_string(height_px) + " pixels");
  const std::size_t pixels = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px);
  auto need = [&](std::size_t bytes) {
    if (size < bytes) {
      throw std::invalid_argument(pixel_format + " frame of " + std::to_string(width_px) + "×" +
                                  std::to_string(height_px) + " needs " + std::to_string(bytes) + " bytes, got " +
                                  std::to_string(size));
    }
  };
  if (pixel_format == "Mono8") {
    need(pixels);
    return cv::Mat(height_px, width_px, CV_8UC1, const_cast<std::uint8_t*>(data)).clone();
  }
  cv::Mat image(height_px, width_px, CV_16UC1);
  auto* out = image.ptr<std::uint16_t>();
  if (pixel_format == "Mono10" || pixel_format == "Mono12" || pixel_format == "Mono16") {
    need(pixels * 2);
    for (std::size_t i = 0; i < pixels; ++i) out[i] = static_cast<std::uint16_t>(data[2 * i] | (data[2 * i + 1] << 8));
    return image;
  }
  const bool gvsp = pixel_format == "Mono10Packed" || pixel_format == "Mono12Packed";
  const bool pfnc = pixel_format == "Mono10p" || pixel_format == "Mono12p";
  if (!gvsp && !pfnc) throw std::invalid_argument("pixel format " + pixel_format + " is not recorded");
  const int bits = pixel_format.starts_with("Mono10") ? 10 : 12;
  const std::size_t bytes = genicam_packed_bytes(pixels, bits, gvsp);
  need(bytes);
  if (gvsp) {
    unpack_gvsp_pairs(data, out, pixels, bits);
  } else if (size >= bytes + 2) {
    unpack_lsb_stream(data, out, pixels, bits);
  } else {
    // The stream reader looks up to two bytes ahead; a buffer cut exactly
    // at the last pixel is read through a padded copy.
    std::vector<std::uint8_t> padded(data, data + bytes);
    padded.resize(bytes + 2, 0);
    unpack_lsb_stream(padded.data(), out, pixels, bits);
  }
  return image;
}

}  // namespace bosfuse::acquisition
