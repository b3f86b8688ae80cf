#include "acquisition/cameras/image_header.h"

#include <jpeglib.h>
// jpeglib.h first: jerror.h needs its types.
#include <jerror.h>
#include <png.h>
#include <tiffio.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <csetjmp>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace bosfuse::acquisition {
namespace {

using namespace std::string_view_literals;

// What a library said when it gave up, kept in a plain buffer: libpng and
// libjpeg report errors by longjmp, so these functions keep no C++ object
// with a destructor between setjmp and the libraries' calls.
struct Complaint {
  char text[JMSG_LENGTH_MAX] = {};
  void say(const char* what) {
    if (!text[0]) std::snprintf(text, sizeof text, "%s", what);
  }
};

// Sequential reading for libpng and libjpeg, stopped at the budget.
struct Cursor {
  ByteSource* source;
  std::uint64_t offset;
  std::uint64_t budget;
  std::size_t read(std::uint8_t* out, std::size_t n) {
    const std::uint64_t left = budget > offset ? budget - offset : 0;
    const std::size_t got = source->read_at(offset, out, static_cast<std::size_t>(std::min<std::uint64_t>(n, left)));
    offset += got;
    return got;
  }
  bool over_budget() const { return offset >= budget; }
};

struct PngState {
  Cursor cursor;
  Complaint complaint;
};

void png_read_from_source(png_structp png, png_bytep out, png_size_t length) {
  auto* state = static_cast<PngState*>(png_get_io_ptr(png));
  if (state->cursor.read(out, length) != length) {
    png_error(png, state->cursor.over_budget() ? "its chunks before the image data are longer than allowed"
                                               : "the file ends inside its header");
  }
}

void png_read_quiet(png_structp, png_const_charp) {}
void png_fail(png_structp png, png_const_charp message) {
  static_cast<PngState*>(png_get_error_ptr(png))->complaint.say(message);
  png_longjmp(png, 1);
}

// Nothing changes between setjmp and the jump but what `size` points to.
bool png_read_size(png_structp png, png_infop info, PngState* state, DeclaredSize* size) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_set_user_limits(png, 0x7fffffff, 0x7fffffff);  // ours are checked by the caller, with a message
  png_set_read_fn(png, state, png_read_from_source);
  png_read_info(png, info);
  size->width_px = png_get_image_width(png, info);
  size->height_px = png_get_image_height(png, info);
  return true;
}

ImageHeader png_header(ByteSource& source, std::uint64_t budget) {
  PngState state{{&source, 0, budget}, {}};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &state, png_fail, png_read_quiet);
  if (!png) return {std::nullopt, "libpng could not start", std::nullopt};
  png_infop info = png_create_info_struct(png);
  DeclaredSize size;
  const bool ok = info && png_read_size(png, info, &state, &size);
  png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  if (!ok) return {std::nullopt, state.complaint.text, std::nullopt};
  return {size, {}, std::nullopt};
}

// libjpeg's errors come here: the first one is kept, then the read ends.
struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  bool reading_data = false;  // past the header: a warning now means missing or damaged pixels
  Complaint complaint;
};

void jpeg_say(j_common_ptr cinfo) {
  char text[JMSG_LENGTH_MAX];
  (*cinfo->err->format_message)(cinfo, text);
  reinterpret_cast<JpegError*>(cinfo->err)->complaint.say(text);
}
void jpeg_fail(j_common_ptr cinfo) {
  jpeg_say(cinfo);
  std::longjmp(reinterpret_cast<JpegError*>(cinfo->err)->jump, 1);
}
void jpeg_warning(j_common_ptr cinfo, int level) {
  if (level < 0 && reinterpret_cast<JpegError*>(cinfo->err)->reading_data) jpeg_say(cinfo);
}

void set_error_manager(jpeg_decompress_struct& cinfo, JpegError& error) {
  cinfo.err = jpeg_std_error(&error.manager);
  error.manager.error_exit = jpeg_fail;
  error.manager.emit_message = jpeg_warning;
}

// A libjpeg source manager over a ByteSource: segments libjpeg skips (EXIF,
// thumbnails) are stepped over, not read.
struct JpegSource {
  jpeg_source_mgr manager;
  Cursor cursor;
  std::array<JOCTET, 16384> buffer;
};

void jpeg_source_init(j_decompress_ptr) {}
void jpeg_source_term(j_decompress_ptr) {}

boolean jpeg_source_fill(j_decompress_ptr cinfo) {
  auto* source = reinterpret_cast<JpegSource*>(cinfo->src);
  std::size_t got = source->cursor.read(source->buffer.data(), source->buffer.size());
  if (got == 0) {  // as libjpeg's own sources do at the end: warn and end the stream
    WARNMS(cinfo, JWRN_JPEG_EOF);
    source->buffer[0] = 0xFF;
    source->buffer[1] = JPEG_EOI;
    got = 2;
  }
  source->manager.next_input_byte = source->buffer.data();
  source->manager.bytes_in_buffer = got;
  return TRUE;
}

void jpeg_source_skip(j_decompress_ptr cinfo, long count) {
  auto* source = reinterpret_cast<JpegSource*>(cinfo->src);
  if (count <= 0) return;
  const auto n = static_cast<std::size_t>(count);
  if (n <= source->manager.bytes_in_buffer) {
    source->manager.next_input_byte += n;
    source->manager.bytes_in_buffer -= n;
    return;
  }
  source->cursor.offset += n - source->manager.bytes_in_buffer;
  source->manager.bytes_in_buffer = 0;
}

// Nothing changes between setjmp and the jump but what `size` points to.
bool jpeg_read_size(jpeg_decompress_struct& cinfo, JpegError& error, JpegSource& source, DeclaredSize* size) {
  if (setjmp(error.jump) != 0) return false;
  jpeg_create_decompress(&cinfo);
  cinfo.src = &source.manager;
  if (jpeg_read_header(&cinfo, TRUE) != JPEG_HEADER_OK) return false;
  size->width_px = cinfo.image_width;
  size->height_px = cinfo.image_height;
  return true;
}

ImageHeader jpeg_header(ByteSource& bytes, std::uint64_t budget) {
  jpeg_decompress_struct cinfo;
  JpegError error;
  set_error_manager(cinfo, error);
  JpegSource source{};
  source.cursor = {&bytes, 0, budget};
  source.manager.init_source = jpeg_source_init;
  source.manager.fill_input_buffer = jpeg_source_fill;
  source.manager.skip_input_data = jpeg_source_skip;
  source.manager.resync_to_restart = jpeg_resync_to_restart;
  source.manager.term_source = jpeg_source_term;
  DeclaredSize size;
  const bool ok = jpeg_read_size(cinfo, error, source, &size);
  jpeg_destroy_decompress(&cinfo);
  if (!ok) return {std::nullopt, error.complaint.text, std::nullopt};
  return {size, {}, std::nullopt};
}

// libtiff reads through these; its errors are kept, its warnings dropped.
struct TiffState {
  ByteSource* source;
  toff_t offset = 0;
  Complaint complaint;
};

tmsize_t tiff_read(thandle_t handle, void* out, tmsize_t length) {
  auto* state = static_cast<TiffState*>(handle);
  if (length <= 0) return 0;
  const std::size_t got =
      state->source->read_at(state->offset, static_cast<std::uint8_t*>(out), static_cast<std::size_t>(length));
  state->offset += got;
  return static_cast<tmsize_t>(got);
}
tmsize_t tiff_write(thandle_t, void*, tmsize_t) { return 0; }
toff_t tiff_seek(thandle_t handle, toff_t offset, int whence) {
  auto* state = static_cast<TiffState*>(handle);
  const toff_t base = whence == SEEK_CUR ? state->offset : whence == SEEK_END ? state->source->size() : 0;
  state->offset = base + offset;
  return state->offset;
}
int tiff_close(thandle_t) { return 0; }
toff_t tiff_size(thandle_t handle) { return static_cast<TiffState*>(handle)->source->size(); }
int tiff_quiet(TIFF*, void*, const char*, const char*, va_list) { return 1; }
int tiff_error(TIFF*, void* user_data, const char*, const char* format, va_list arguments) {
  auto& complaint = static_cast<TiffState*>(user_data)->complaint;
  if (!complaint.text[0]) std::vsnprintf(complaint.text, sizeof complaint.text, format, arguments);
  return 1;
}

// Past the last byte of the first image's strips (or tiles).
std::uint64_t tiff_data_end(TIFF* tiff) {
  const std::uint32_t striles = TIFFIsTiled(tiff) ? TIFFNumberOfTiles(tiff) : TIFFNumberOfStrips(tiff);
  std::uint64_t end = 0;
  for (std::uint32_t i = 0; i < striles; ++i) {
    const std::uint64_t offset = TIFFGetStrileOffset(tiff, i), count = TIFFGetStrileByteCount(tiff, i);
    if (count > 0) end = std::max(end, offset + count);
  }
  return end;
}

ImageHeader tiff_header(ByteSource& source, std::uint64_t budget) {
  TiffState state{&source, 0, {}};
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  TIFFOpenOptionsSetErrorHandlerExtR(options, tiff_error, &state);
  TIFFOpenOptionsSetWarningHandlerExtR(options, tiff_quiet, nullptr);
  TIFFOpenOptionsSetMaxSingleMemAlloc(options, static_cast<tmsize_t>(budget));
  TIFF* tiff = TIFFClientOpenExt("memory", "rm", &state, tiff_read, tiff_write, tiff_seek, tiff_close, tiff_size,
                                 nullptr, nullptr, options);
  TIFFOpenOptionsFree(options);
  if (!tiff) return {std::nullopt, state.complaint.text, std::nullopt};
  std::uint32_t width = 0, height = 0;
  ImageHeader header;
  if (TIFFGetField(tiff, TIFFTAG_IMAGEWIDTH, &width) && TIFFGetField(tiff, TIFFTAG_IMAGELENGTH, &height)) {
    header.size = DeclaredSize{width, height};
    header.data_end = tiff_data_end(tiff);
  } else {
    header.problem = "its first directory has no image width and length";
  }
  TIFFClose(tiff);
  return header;
}

// BMP: the DIB header's width and height (16-bit in the old core header,
// else 32-bit, little-endian; a negative height is a top-down image).
ImageHeader bmp_header(ByteSource& source) {
  std::array<std::uint8_t, 26> bytes{};
  if (source.read_at(0, bytes.data(), bytes.size()) != bytes.size())
    return {std::nullopt, "the file ends inside its header", std::nullopt};
  const auto le = [&](std::size_t at, int n) {
    std::uint32_t v = 0;
    for (int i = n - 1; i >= 0; --i) v = (v << 8) | bytes[at + static_cast<std::size_t>(i)];
    return v;
  };
  if (le(14, 4) == 12) return {DeclaredSize{le(18, 2), le(20, 2)}, {}, std::nullopt};
  const auto width = static_cast<std::int32_t>(le(18, 4));
  const auto height = static_cast<std::int32_t>(le(22, 4));
  return {DeclaredSize{std::abs(static_cast<std::int64_t>(width)), std::abs(static_cast<std::int64_t>(height))},
          {},
          std::nullopt};
}

// PNM: width and height are the first two numbers after the magic, with
// whitespace and '#' comments between them. Every digit counts, as OpenCV
// reads them: cutting a number short let "P6 0000000000" + "27565 27568"
// pass as 0x27565 px while OpenCV decoded 27565x27568 (2.3 GB; found by
// fuzzing). A number past any limit saturates instead of overflowing.
ImageHeader pnm_header(ByteSource& source, std::uint64_t budget) {
  constexpr std::int64_t kPastAnyLimit = 1'000'000'000'000'000;
  std::array<std::uint8_t, 4096> block;
  std::uint64_t block_at = 0;
  std::size_t block_size = 0;
  const auto byte_at = [&](std::uint64_t at) -> int {  // -1 past the end or the budget
    if (at >= budget) return -1;
    if (at < block_at || at >= block_at + block_size) {
      block_at = at;
      block_size = source.read_at(at, block.data(), block.size());
      if (block_size == 0) return -1;
    }
    return block[at - block_at];
  };
  std::uint64_t at = 2;
  std::int64_t numbers[2] = {0, 0};
  for (std::int64_t& number : numbers) {
    for (;;) {
      while (byte_at(at) >= 0 && std::isspace(byte_at(at))) ++at;
      if (byte_at(at) != '#') break;
      while (byte_at(at) >= 0 && byte_at(at) != '\n' && byte_at(at) != '\r') ++at;
    }
    const std::uint64_t first = at;
    while (byte_at(at) >= 0 && std::isdigit(byte_at(at)))
      number = std::min(number * 10 + (byte_at(at++) - '0'), kPastAnyLimit);
    if (at == first) return {std::nullopt, "its header has no width and height", std::nullopt};
  }
  return {DeclaredSize{numbers[0], numbers[1]}, {}, std::nullopt};
}

bool starts_with(std::span<const std::uint8_t> bytes, std::string_view magic) {
  return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
}

}  // namespace

std::size_t MemoryBytes::read_at(std::uint64_t offset, std::uint8_t* out, std::size_t n) {
  if (offset >= bytes_.size()) return 0;
  const std::size_t got = static_cast<std::size_t>(std::min<std::uint64_t>(n, bytes_.size() - offset));
  std::memcpy(out, bytes_.data() + offset, got);
  return got;
}

std::string_view format_name(ImageFormat format) {
  switch (format) {
    case ImageFormat::kPng:
      return "PNG";
    case ImageFormat::kJpeg:
      return "JPEG";
    case ImageFormat::kTiff:
      return "TIFF";
    case ImageFormat::kBmp:
      return "BMP";
    case ImageFormat::kPnm:
      return "PNM";
  }
  return "image";
}

// Each signature as OpenCV recognises it. OpenCV tries its decoders in
// turn, these before GDCM (DICOM) and GDAL, whose decoders allocate before
// any limit is consulted and abort on forged headers: a 166-byte DICOM
// header asked for 1.7 GB, and bytes starting "P5" but with "DICM" at
// offset 128 reached GDCM's assert (both found by fuzzing). PNM is P1…P6
// and then a space: "P5" followed by anything else is no PNM to OpenCV.
std::optional<ImageFormat> image_format(ByteSource& source) {
  std::array<std::uint8_t, 8> first{};
  const std::span<const std::uint8_t> bytes(first.data(), source.read_at(0, first.data(), first.size()));
  if (starts_with(bytes, "\x89PNG\r\n\x1a\n"sv)) return ImageFormat::kPng;
  if (starts_with(bytes, "\xff\xd8\xff"sv)) return ImageFormat::kJpeg;
  for (const std::string_view tiff : {"II*\0"sv, "MM\0*"sv, "II+\0"sv, "MM\0+"sv}) {
    if (starts_with(bytes, tiff)) return ImageFormat::kTiff;
  }
  if (starts_with(bytes, "BM"sv)) return ImageFormat::kBmp;
  if (bytes.size() >= 3 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6' && std::isspace(bytes[2])) {
    return ImageFormat::kPnm;
  }
  return std::nullopt;
}

ImageHeader read_image_header(ByteSource& source, ImageFormat format, std::uint64_t budget_bytes) {
  ImageHeader header;
  switch (format) {
    case ImageFormat::kPng:
      header = png_header(source, budget_bytes);
      break;
    case ImageFormat::kJpeg:
      header = jpeg_header(source, budget_bytes);
      break;
    case ImageFormat::kTiff:
      header = tiff_header(source, budget_bytes);
      break;
    case ImageFormat::kBmp:
      header = bmp_header(source);
      break;
    case ImageFormat::kPnm:
      header = pnm_header(source, budget_bytes);
      break;
  }
  if (!header.size && header.problem.empty()) header.problem = "its header cannot be read";
  return header;
}

std::string jpeg_data_problem(std::span<const std::uint8_t> bytes) {
  jpeg_decompress_struct cinfo;
  JpegError error;
  set_error_manager(cinfo, error);
  if (setjmp(error.jump) == 0) {
    jpeg_create_decompress(&cinfo);
    jpeg_mem_src(&cinfo, bytes.data(), static_cast<unsigned long>(bytes.size()));
    jpeg_read_header(&cinfo, TRUE);
    error.reading_data = true;
    // Every coefficient is still entropy-decoded; at 1/8 scale only the DC
    // term of each block is transformed back, and no pixel is smoothed.
    cinfo.scale_num = 1;
    cinfo.scale_denom = 8;
    cinfo.dct_method = JDCT_IFAST;
    cinfo.do_fancy_upsampling = FALSE;
    cinfo.do_block_smoothing = FALSE;
    jpeg_start_decompress(&cinfo);
    const JDIMENSION row_samples = cinfo.output_width * static_cast<JDIMENSION>(cinfo.output_components);
    JSAMPARRAY row = (*cinfo.mem->alloc_sarray)(reinterpret_cast<j_common_ptr>(&cinfo), JPOOL_IMAGE, row_samples, 1);
    while (cinfo.output_scanline < cinfo.output_height) jpeg_read_scanlines(&cinfo, row, 1);
    jpeg_finish_decompress(&cinfo);
  }
  jpeg_destroy_decompress(&cinfo);
  return error.complaint.text;
}

}  // namespace bosfuse::acquisition
