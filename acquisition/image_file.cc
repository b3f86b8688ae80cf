#include "acquisition/image_file.h"

#include <fmt/format.h>
#include <jpeglib.h>
#include <png.h>
#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <csetjmp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace bosfuse::acquisition {
namespace {

using namespace std::string_view_literals;

std::int64_t limit_from_environment(const char* variable, std::int64_t fallback) {
  const char* text = std::getenv(variable);
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const long long value = std::strtoll(text, &end, 10);
  if (*end != '\0' || value <= 0) {
    throw std::invalid_argument(fmt::format("{}='{}' must be a positive whole number", variable, text));
  }
  return value;
}

// libpng and libjpeg report errors by longjmp; these functions keep no C++
// object with a destructor between setjmp and the libraries' calls.
struct PngSource {
  const std::uint8_t* data;
  std::size_t size, offset;
};

void png_read_from_memory(png_structp png, png_bytep out, png_size_t length) {
  auto* source = static_cast<PngSource*>(png_get_io_ptr(png));
  if (length > source->size - source->offset) png_error(png, "truncated");
  std::memcpy(out, source->data + source->offset, length);
  source->offset += length;
}

void png_quiet(png_structp, png_const_charp) {}
void png_fail(png_structp png, png_const_charp) { png_longjmp(png, 1); }

bool png_header_size(const std::uint8_t* data, std::size_t size, png_uint_32& width, png_uint_32& height) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, png_fail, png_quiet);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  PngSource source{data, size, 0};
  bool ok = false;
  if (info && setjmp(png_jmpbuf(png)) == 0) {
    png_set_user_limits(png, 0x7fffffff, 0x7fffffff);  // ours are checked by the caller, with a message
    png_set_read_fn(png, &source, png_read_from_memory);
    png_read_info(png, info);
    width = png_get_image_width(png, info);
    height = png_get_image_height(png, info);
    ok = true;
  }
  png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  return ok;
}

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
};

void jpeg_fail(j_common_ptr cinfo) { std::longjmp(reinterpret_cast<JpegError*>(cinfo->err)->jump, 1); }
void jpeg_quiet(j_common_ptr, int) {}

bool jpeg_header_size(const std::uint8_t* data, std::size_t size, JDIMENSION& width, JDIMENSION& height) {
  jpeg_decompress_struct cinfo;
  JpegError error;
  cinfo.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = jpeg_fail;
  error.manager.emit_message = jpeg_quiet;
  bool ok = false;
  if (setjmp(error.jump) == 0) {
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, data, static_cast<unsigned long>(size));
    if (jpeg_read_header(&cinfo, TRUE) == JPEG_HEADER_OK) {
      width = cinfo.image_width;
      height = cinfo.image_height;
      ok = true;
    }
  }
  jpeg_destroy_decompress(&cinfo);
  return ok;
}

// libtiff reads through these from memory; errors go to a handler that
// stays quiet (a TIFF we cannot read is reported by the caller).
struct TiffSource {
  std::span<const std::uint8_t> bytes;
  toff_t offset = 0;
};

tmsize_t tiff_read(thandle_t handle, void* out, tmsize_t length) {
  auto* source = static_cast<TiffSource*>(handle);
  const auto available = source->offset < source->bytes.size() ? source->bytes.size() - source->offset : 0;
  const auto n = std::min<std::uint64_t>(static_cast<std::uint64_t>(length), available);
  std::memcpy(out, source->bytes.data() + source->offset, n);
  source->offset += n;
  return static_cast<tmsize_t>(n);
}
tmsize_t tiff_write(thandle_t, void*, tmsize_t) { return 0; }
toff_t tiff_seek(thandle_t handle, toff_t offset, int whence) {
  auto* source = static_cast<TiffSource*>(handle);
  const toff_t base = whence == SEEK_CUR ? source->offset : whence == SEEK_END ? source->bytes.size() : 0;
  source->offset = base + offset;
  return source->offset;
}
int tiff_close(thandle_t) { return 0; }
toff_t tiff_size(thandle_t handle) { return static_cast<TiffSource*>(handle)->bytes.size(); }
int tiff_quiet(TIFF*, void*, const char*, const char*, va_list) { return 1; }

std::optional<DeclaredSize> tiff_header_size(std::span<const std::uint8_t> bytes) {
  TiffSource source{bytes};
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options, tiff_quiet, nullptr);
  TIFFOpenOptionsSetWarningHandlerExtR(options, tiff_quiet, nullptr);
  TIFF* tiff = TIFFClientOpenExt("memory", "rm", &source, tiff_read, tiff_write, tiff_seek, tiff_close, tiff_size,
                                 nullptr, nullptr, options);
  TIFFOpenOptionsFree(options);
  if (!tiff) return std::nullopt;
  std::uint32_t width = 0, height = 0;
  const bool ok = TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &width) && TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &height);
  TIFFClose(tiff);
  if (!ok) return std::nullopt;
  return DeclaredSize{width, height};
}

bool starts_with(std::span<const std::uint8_t> bytes, std::string_view magic) {
  return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
}

// PNM as OpenCV recognises it: P1…P6 and then a space. "P5" followed by
// anything else is no PNM to OpenCV, which then tries its later decoders.
bool is_pnm(std::span<const std::uint8_t> bytes) {
  return bytes.size() >= 3 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6' &&
         std::isspace(static_cast<unsigned char>(bytes[2]));
}

// The formats bosfuse reads: PNG, JPEG, TIFF, BMP and PNM, each recognised
// exactly as OpenCV recognises it. OpenCV tries its decoders in turn, these
// before GDCM (DICOM) and GDAL, whose decoders allocate before any limit
// is consulted and abort on forged headers: a 166-byte DICOM header asked
// for 1.7 GB, and bytes starting "P5" but with "DICM" at offset 128 reached
// GDCM's assert (both found by fuzzing).
bool is_format_read(std::span<const std::uint8_t> bytes) {
  static constexpr std::string_view kSignatures[] = {
      "\x89PNG\r\n\x1a\n"sv, "\xff\xd8\xff"sv, "II*\0"sv, "MM\0*"sv, "II+\0"sv, "MM\0+"sv, "BM"sv};
  for (const std::string_view signature : kSignatures) {
    if (starts_with(bytes, signature)) return true;
  }
  return is_pnm(bytes);
}

// PNM: width and height are the first two numbers after the magic, with
// whitespace and '#' comments between them. Every digit counts, as OpenCV
// reads them: cutting a number short let "P6 0000000000" + "27565 27568"
// pass as 0x27565 px while OpenCV decoded 27565x27568 (2.3 GB; found by
// fuzzing). A number past any limit saturates instead of overflowing.
std::optional<DeclaredSize> pnm_header_size(std::span<const std::uint8_t> bytes) {
  constexpr std::int64_t kPastAnyLimit = 1'000'000'000'000'000;
  std::size_t at = 2;
  std::int64_t numbers[2] = {0, 0};
  for (std::int64_t& number : numbers) {
    for (;;) {
      while (at < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[at]))) ++at;
      if (at >= bytes.size() || bytes[at] != '#') break;
      while (at < bytes.size() && bytes[at] != '\n' && bytes[at] != '\r') ++at;
    }
    const std::size_t first = at;
    while (at < bytes.size() && std::isdigit(static_cast<unsigned char>(bytes[at]))) {
      number = std::min(number * 10 + (bytes[at++] - '0'), kPastAnyLimit);
    }
    if (at == first) return std::nullopt;
  }
  return DeclaredSize{numbers[0], numbers[1]};
}

}  // namespace

ImageLimits ImageLimits::from_environment() {
  ImageLimits limits;
  limits.max_pixels = limit_from_environment("BOSFUSE_MAX_IMAGE_PIXELS", limits.max_pixels);
  limits.max_side_px = limit_from_environment("BOSFUSE_MAX_IMAGE_SIDE_PX", limits.max_side_px);
  return limits;
}

// BMP: the DIB header's width and height (16-bit in the old core header,
// else 32-bit, little-endian; a negative height is a top-down image).
std::optional<DeclaredSize> bmp_header_size(std::span<const std::uint8_t> bytes) {
  const auto le = [&](std::size_t at, int n) {
    std::uint32_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | bytes[at + static_cast<std::size_t>(i)];
    return v;
  };
  if (bytes.size() < 26) return std::nullopt;
  if (le(14, 4) == 12) return DeclaredSize{le(18, 2), le(20, 2)};
  const auto width = static_cast<std::int32_t>(le(18, 4));
  const auto height = static_cast<std::int32_t>(le(22, 4));
  return DeclaredSize{std::abs(static_cast<std::int64_t>(width)), std::abs(static_cast<std::int64_t>(height))};
}

std::optional<DeclaredSize> declared_image_size(std::span<const std::uint8_t> bytes) {
  if (starts_with(bytes, "\x89PNG\r\n\x1a\n"sv)) {
    png_uint_32 width = 0, height = 0;
    if (png_header_size(bytes.data(), bytes.size(), width, height)) return DeclaredSize{width, height};
  } else if (starts_with(bytes, "\xff\xd8\xff"sv)) {
    JDIMENSION width = 0, height = 0;
    if (jpeg_header_size(bytes.data(), bytes.size(), width, height)) return DeclaredSize{width, height};
  } else if (starts_with(bytes, "II*\0"sv) || starts_with(bytes, "MM\0*"sv) || starts_with(bytes, "II+\0"sv) ||
             starts_with(bytes, "MM\0+"sv)) {
    return tiff_header_size(bytes);
  } else if (starts_with(bytes, "BM"sv)) {
    return bmp_header_size(bytes);
  } else if (is_pnm(bytes)) {
    return pnm_header_size(bytes);
  }
  return std::nullopt;
}

cv::Mat decode_image(std::span<const std::uint8_t> bytes, const std::string& name, const ImageLimits& limits) {
  if (const auto size = declared_image_size(bytes)) {
    // In double: two 32-bit sides (TIFF) multiply past int64.
    const double pixels = static_cast<double>(size->width_px) * static_cast<double>(size->height_px);
    if (size->width_px > limits.max_side_px || size->height_px > limits.max_side_px ||
        pixels > static_cast<double>(limits.max_pixels)) {
      throw ImageTooLarge(fmt::format(
          "{}: the image declares {}x{} px ({:.1f} megapixels), over the limit of {} px a side and {:.1f} "
          "megapixels (BOSFUSE_MAX_IMAGE_SIDE_PX, BOSFUSE_MAX_IMAGE_PIXELS); not decoded",
          name, size->width_px, size->height_px, pixels * 1e-6, limits.max_side_px, limits.max_pixels * 1e-6));
    }
  }
  if (!is_format_read(bytes) || bytes.size() > static_cast<std::size_t>(INT_MAX)) return {};
  const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8U, const_cast<std::uint8_t*>(bytes.data()));
  try {
    return cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    return {};  // OpenCV's own checks refused it: no image we can decode
  }
}

cv::Mat read_image_file(const std::filesystem::path& path, const ImageLimits& limits) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return {};
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return {};
  const auto size = in.tellg();
  if (size <= 0) return {};
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  in.seekg(0);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), size)) return {};
  return decode_image(bytes, path.string(), limits);
}

}  // namespace bosfuse::acquisition
