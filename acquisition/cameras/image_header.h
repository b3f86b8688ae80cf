#pragma once
// What an image file's header says, read with the format's own library
// (libpng, libjpeg, libtiff; BMP and PNM by their few fixed fields) from a
// ByteSource: a file read only where the library asks, never whole, or
// bytes in memory. acquisition/cameras/image_file.h checks these against its limits
// before anything is read whole or decoded; use that, not this, to read an
// image. Here too is the one check that needs the image data: libjpeg's own
// reading of a JPEG's whole entropy-coded data, which finds a truncated
// JPEG that OpenCV's decoder accepts with no more than a warning.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace bosfuse::acquisition {

// Bytes read where asked, so a header is read without the rest of the file.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::uint64_t size() const = 0;
  // Up to `n` bytes from `offset` into `out`; fewer at the end of the bytes
  // or on a read error (which a header reader then finds short).
  virtual std::size_t read_at(std::uint64_t offset, std::uint8_t* out, std::size_t n) = 0;
};

class MemoryBytes : public ByteSource {
 public:
  explicit MemoryBytes(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  std::size_t read_at(std::uint64_t offset, std::uint8_t* out, std::size_t n) override;

 private:
  std::span<const std::uint8_t> bytes_;
};

// The formats bosfuse decodes, each recognised by its signature exactly as
// OpenCV recognises it.
enum class ImageFormat { kPng, kJpeg, kTiff, kBmp, kPnm };

std::string_view format_name(ImageFormat format);  // "PNG", "JPEG", …

// The format the first bytes announce; nullopt for any other bytes.
std::optional<ImageFormat> image_format(ByteSource& source);

// What a header declares: 64-bit, since a TIFF may declare 2^32 - 1 a side.
struct DeclaredSize {
  std::int64_t width_px = 0;
  std::int64_t height_px = 0;
};

struct ImageHeader {
  std::optional<DeclaredSize> size;  // nullopt: the header could not be read
  std::string problem;               // why not, in the library's words
  // TIFF: the byte just past the first image's last strip or tile, as its
  // directory states; a file shorter than that is truncated.
  std::optional<std::uint64_t> data_end;
};

// Reads the header of a `format` image from `source`. The library may read
// at most `budget_bytes` (everything before the pixels: PNG chunks, TIFF
// tag arrays); a header that needs more is unreadable.
ImageHeader read_image_header(ByteSource& source, ImageFormat format, std::uint64_t budget_bytes);

// libjpeg reading all of a JPEG's image data (scaled to 1/8 while decoding;
// the entropy decoding it cannot skip is still about half a full decode's
// cost: 183 ms against 381 ms for a 12 MP colour JPEG of 7 MB, measured
// while another build ran). Empty when it found the data complete and
// sound; otherwise the first warning or error libjpeg gave
// while reading the image data ("Premature end of JPEG file", "Corrupt JPEG
// data: premature end of data segment"). Warnings about metadata in the
// header do not count.
std::string jpeg_data_problem(std::span<const std::uint8_t> bytes);

}  // namespace bosfuse::acquisition
