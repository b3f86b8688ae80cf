#pragma once
// Pixels of a GenICam frame as an image bosfuse stores: Mono8 as 8-bit,
// every deeper mono format as 16-bit with the sensor's values unchanged
// (a Mono12 pixel of 4095 stays 4095, not shifted to 65520), so a frame is
// kept losslessly at the sensor's depth. Packed formats are unpacked: the
// GigE Vision layouts Mono10Packed/Mono12Packed (two pixels in three
// bytes, the high bits first) and the PFNC layouts Mono10p/Mono12p (bits
// packed from the least significant end). Unpacked multi-byte formats are
// little-endian on the wire, as GenICam's PFNC says.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace bosfuse::acquisition {

// Throws std::invalid_argument for a format it does not know or a buffer
// shorter than width × height pixels of it.
cv::Mat genicam_pixels_to_image(const std::string& pixel_format, const std::uint8_t* data, std::size_t size,
                                int width_px, int height_px);

}  // namespace bosfuse::acquisition
