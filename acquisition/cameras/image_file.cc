#include "acquisition/cameras/image_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <new>
#include <opencv2/imgcodecs.hpp>

namespace bosfuse::acquisition {
namespace {

std::int64_t limit_from_environment(const char* variable, std::int64_t fallback, std::int64_t unit = 1) {
  const char* text = std::getenv(variable);
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const long long value = std::strtoll(text, &end, 10);
  if (*end != '\0' || value <= 0 || value > LLONG_MAX / unit) {
    throw std::invalid_argument(fmt::format("{}='{}' must be a positive whole number", variable, text));
  }
  return value * unit;
}

// The deepest pixel each format can hold, in bytes, uncompressed: PNG
// 16-bit RGBA; JPEG four 8-bit components (CMYK); TIFF four 64-bit samples;
// BMP 32 bits; PNM three samples written out as text ("65535 "). At
// quality 100, random noise takes a JPEG 1.6 bytes a grey pixel and 2 a
// colour one, well inside twice this.
double deepest_pixel_bytes(ImageFormat format) {
  switch (format) {
    case ImageFormat::kPng:
      return 8;
    case ImageFormat::kJpeg:
      return 4;
    case ImageFormat::kTiff:
      return 32;
    case ImageFormat::kBmp:
      return 4;
    case ImageFormat::kPnm:
      return 18;
  }
  return 32;
}

std::string megabytes(double bytes) { return fmt::format("{:.1f} MB", bytes * 1e-6); }

// The header's pixels against the limits (in double: two 32-bit TIFF sides
// multiply past int64).
void check_declared_size(DeclaredSize size, const std::string& name, const ImageLimits& limits) {
  const double pixels = static_cast<double>(size.width_px) * static_cast<double>(size.height_px);
  if (size.width_px > limits.max_side_px || size.height_px > limits.max_side_px ||
      pixels > static_cast<double>(limits.max_pixels)) {
    throw ImageTooLarge(
        fmt::format("{}: the image declares {}x{} px ({:.1f} megapixels), over the limit of {} px a side and {:.1f} "
                    "megapixels (BOSFUSE_MAX_IMAGE_SIDE_PX, BOSFUSE_MAX_IMAGE_PIXELS); not decoded",
                    name, size.width_px, size.height_px, pixels * 1e-6, limits.max_side_px, limits.max_pixels * 1e-6));
  }
}

// The file's size against what the declared pixels can need: what catches
// a small image padded (or followed) by gigabytes.
void check_file_size_for(ImageFormat format, DeclaredSize size, std::uint64_t file_bytes, const std::string& name,
                         const ImageLimits& limits) {
  const std::int64_t most = limits.max_file_bytes(format, size);
  if (file_bytes <= static_cast<std::uint64_t>(most)) return;
  throw ImageTooLarge(fmt::format(
      "{}: the file is {} bytes ({}), more than a {}x{} px {} can need (at most {} bytes: twice {} bytes a pixel, "
      "plus {} of metadata, BOSFUSE_MAX_IMAGE_METADATA_MB); not read",
      name, file_bytes, megabytes(static_cast<double>(file_bytes)), size.width_px, size.height_px, format_name(format),
      most, deepest_pixel_bytes(format), megabytes(static_cast<double>(limits.max_metadata_bytes))));
}

struct CheckedHeader {
  ImageFormat format;
  DeclaredSize size;
};

// Everything that needs only the header and the file's size; nullopt when
// the bytes are of no format bosfuse reads.
std::optional<CheckedHeader> check_before_reading(ByteSource& source, const std::string& name,
                                                  const ImageLimits& limits) {
  const auto format = image_format(source);
  if (!format) return std::nullopt;
  const auto header_budget = static_cast<std::uint64_t>(limits.max_metadata_bytes);
  const ImageHeader header = read_image_header(source, *format, header_budget);
  if (!header.size) {
    throw ImageUnreadable(fmt::format("{}: not a readable {}: {}", name, format_name(*format), header.problem));
  }
  check_declared_size(*header.size, name, limits);
  check_file_size_for(*format, *header.size, source.size(), name, limits);
  if (header.data_end && *header.data_end > source.size()) {
    throw ImageUnreadable(fmt::format("{}: truncated: the TIFF's image data runs to byte {}, the file has {} bytes",
                                      name, *header.data_end, source.size()));
  }
  return CheckedHeader{*format, *header.size};
}

std::string out_of_memory(const std::string& name, const CheckedHeader& header) {
  return fmt::format("{}: out of memory decoding its {}x{} px {} image", name, header.size.width_px,
                     header.size.height_px, format_name(header.format));
}

cv::Mat decode_with_opencv(std::span<const std::uint8_t> bytes, const std::string& name, const CheckedHeader& header) {
  const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8U, const_cast<std::uint8_t*>(bytes.data()));
  cv::Mat image;
  try {
    image = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const std::bad_alloc&) {
    throw ImageUnreadable(out_of_memory(name, header));
  } catch (const cv::Exception& e) {
    if (e.code == cv::Error::StsNoMem) throw ImageUnreadable(out_of_memory(name, header));
    throw ImageUnreadable(
        fmt::format("{}: OpenCV cannot decode this {}: {}", name, format_name(header.format), e.what()));
  }
  // OpenCV's decoders give up on a PNG, TIFF, BMP or PNM whose data ends
  // early or is damaged with an empty image (and a complaint on standard
  // error that names no file).
  if (image.empty()) {
    throw ImageUnreadable(
        fmt::format("{}: the {}'s image data is incomplete or damaged (truncated?); its {}x{} px "
                    "could not be decoded",
                    name, format_name(header.format), header.size.width_px, header.size.height_px));
  }
  return image;
}

// A file descriptor, closed when it goes.
class OpenFile {
 public:
  explicit OpenFile(int fd) : fd_(fd) {}
  ~OpenFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};

// pread until `n` bytes or the end; -1 on an error.
std::int64_t read_fully_at(int fd, std::uint8_t* out, std::uint64_t n, std::uint64_t offset) {
  std::uint64_t done = 0;
  while (done < n) {
    const ssize_t got = ::pread(fd, out + done, n - done, static_cast<off_t>(offset + done));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) return -1;
    if (got == 0) break;
    done += static_cast<std::uint64_t>(got);
  }
  return static_cast<std::int64_t>(done);
}

// A file's bytes read where a header reader asks, a block at a time.
class FileBytes : public ByteSource {
 public:
  FileBytes(int fd, std::uint64_t size) : fd_(fd), size_(size) {}
  std::uint64_t size() const override { return size_; }
  std::size_t read_at(std::uint64_t offset, std::uint8_t* out, std::size_t n) override {
    std::size_t done = 0;
    while (done < n && offset + done < size_) {
      const std::uint64_t at = offset + done;
      if (at < block_at_ || at >= block_at_ + block_size_) {
        const std::int64_t got = read_fully_at(fd_, block_.data(), block_.size(), at);
        if (got <= 0) break;
        block_at_ = at;
        block_size_ = static_cast<std::size_t>(got);
      }
      const std::size_t take = std::min<std::uint64_t>(n - done, block_at_ + block_size_ - at);
      std::memcpy(out + done, block_.data() + (at - block_at_), take);
      done += take;
    }
    return done;
  }

 private:
  int fd_;
  std::uint64_t size_;
  std::array<std::uint8_t, 65536> block_;
  std::uint64_t block_at_ = 0;
  std::size_t block_size_ = 0;
};

std::vector<std::uint8_t> read_whole(int fd, std::uint64_t size, const std::string& name) {
  std::vector<std::uint8_t> bytes;
  try {
    bytes.resize(size);
  } catch (const std::bad_alloc&) {
    throw ImageUnreadable(
        fmt::format("{}: out of memory for its {} bytes ({})", name, size, megabytes(static_cast<double>(size))));
  }
  const std::int64_t got = read_fully_at(fd, bytes.data(), size, 0);
  if (got < 0) throw ImageUnreadable(fmt::format("{}: cannot be read: {}", name, std::strerror(errno)));
  bytes.resize(static_cast<std::size_t>(got));  // shorter when it shrank meanwhile; decode_image checks it again
  return bytes;
}

}  // namespace

ImageLimits ImageLimits::from_environment() {
  ImageLimits limits;
  limits.max_pixels = limit_from_environment("BOSFUSE_MAX_IMAGE_PIXELS", limits.max_pixels);
  limits.max_side_px = limit_from_environment("BOSFUSE_MAX_IMAGE_SIDE_PX", limits.max_side_px);
  limits.max_metadata_bytes =
      limit_from_environment("BOSFUSE_MAX_IMAGE_METADATA_MB", limits.max_metadata_bytes, 1'000'000);
  return limits;
}

std::int64_t ImageLimits::max_file_bytes(ImageFormat format, DeclaredSize size) const {
  const double pixels = static_cast<double>(size.width_px) * static_cast<double>(size.height_px);
  const double most = 2 * pixels * deepest_pixel_bytes(format) + static_cast<double>(max_metadata_bytes);
  return most >= 9e18 ? INT64_MAX : static_cast<std::int64_t>(most);
}

std::int64_t ImageLimits::max_file_bytes() const {
  return max_file_bytes(ImageFormat::kTiff, DeclaredSize{max_pixels, 1});
}

std::optional<DeclaredSize> declared_image_size(std::span<const std::uint8_t> bytes) {
  MemoryBytes source(bytes);
  const auto format = image_format(source);
  if (!format) return std::nullopt;
  return read_image_header(source, *format, bytes.size()).size;
}

namespace {

// Whatever else a reader throws (no memory for libpng's or libtiff's own
// buffers, an exception from OpenCV) also names the file.
template <typename Read>
auto naming_the_file(const std::string& name, Read read) {
  try {
    return read();
  } catch (const ImageRefused&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw ImageUnreadable(name + ": out of memory reading it");
  } catch (const std::exception& e) {
    throw ImageUnreadable(name + ": " + e.what());
  }
}

cv::Mat checked_decode(std::span<const std::uint8_t> bytes, const std::string& name, const ImageLimits& limits) {
  MemoryBytes source(bytes);
  const auto header = check_before_reading(source, name, limits);
  if (!header) return {};
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) {
    throw ImageTooLarge(
        fmt::format("{}: the file is {} bytes, more than OpenCV decodes from memory (2 GiB)", name, bytes.size()));
  }
  if (header->format == ImageFormat::kJpeg) {
    if (const std::string problem = jpeg_data_problem(bytes); !problem.empty()) {
      throw ImageUnreadable(
          fmt::format("{}: the JPEG's image data is incomplete or damaged (libjpeg: {})", name, problem));
    }
  }
  return decode_with_opencv(bytes, name, *header);
}

std::vector<std::uint8_t> checked_read(const std::filesystem::path& path, const std::string& name,
                                       const ImageLimits& limits) {
  // Non-blocking: a FIFO named like an image must not hang the open.
  const OpenFile file(::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK));
  if (file.fd() < 0) {
    if (errno == ENOENT || errno == ENOTDIR) return {};
    throw ImageUnreadable(fmt::format("{}: cannot be opened: {}", name, std::strerror(errno)));
  }
  struct stat status {};
  if (::fstat(file.fd(), &status) != 0 || !S_ISREG(status.st_mode)) return {};
  const auto size = static_cast<std::uint64_t>(status.st_size);
  if (size > static_cast<std::uint64_t>(limits.max_file_bytes())) {
    throw ImageTooLarge(
        fmt::format("{}: the file is {} bytes ({}), more than any image within the limits can need ({} bytes; "
                    "BOSFUSE_MAX_IMAGE_PIXELS, BOSFUSE_MAX_IMAGE_METADATA_MB); not read",
                    name, size, megabytes(static_cast<double>(size)), limits.max_file_bytes()));
  }
  FileBytes source(file.fd(), size);
  if (!check_before_reading(source, name, limits)) return {};
  return read_whole(file.fd(), size, name);
}

}  // namespace

cv::Mat decode_image(std::span<const std::uint8_t> bytes, const std::string& name, const ImageLimits& limits) {
  return naming_the_file(name, [&] { return checked_decode(bytes, name, limits); });
}

std::vector<std::uint8_t> read_image_bytes(const std::filesystem::path& path, const ImageLimits& limits) {
  const std::string name = path.string();
  return naming_the_file(name, [&] { return checked_read(path, name, limits); });
}

cv::Mat read_image_file(const std::filesystem::path& path, const ImageLimits& limits) {
  const std::vector<std::uint8_t> bytes = read_image_bytes(path, limits);
  if (bytes.empty()) return {};
  return decode_image(bytes, path.string(), limits);
}

}  // namespace bosfuse::acquisition
