#pragma once
// The capture time a camera wrote into an image's EXIF data: DateTimeOriginal
// (tag 0x9003) with SubSecTimeOriginal (0x9291) and OffsetTimeOriginal
// (0x9011) when present, read from a JPEG's APP1 segment or a TIFF file (and
// TIFF-based raw formats). EXIF times are the camera's wall clock, usually
// local time without a zone; exif_capture_time_ns() reads them as UTC and
// applies the offset when the camera recorded one, so the caller adds its
// configured camera-clock offset to reach host UTC.

#include <cstdint>
#include <optional>
#include <span>

namespace bosfuse::acquisition {

struct ExifCaptureTime {
  std::int64_t t_ns = 0;         // the camera's clock, as if it were UTC (or corrected by its offset)
  bool had_zone_offset = false;  // OffsetTimeOriginal was present and applied
};

// nullopt when the file has no readable capture time.
std::optional<ExifCaptureTime> exif_capture_time(std::span<const std::uint8_t> file_bytes);

}  // namespace bosfuse::acquisition
