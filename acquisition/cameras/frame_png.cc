#include "acquisition/cameras/frame_png.h"

#include <fmt/format.h>
#include <png.h>
#include <zlib.h>

#include <bit>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace bosfuse::acquisition {
namespace {

// libpng reports errors by longjmp: its message is kept in a plain buffer,
// and write_rows holds no object with a destructor across its calls.
struct PngError {
  char message[256];
};

void png_write_failed(png_structp png, png_const_charp message) {
  auto* error = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(error->message, sizeof error->message, "%s", message);
  png_longjmp(png, 1);
}

void png_write_quiet(png_structp, png_const_charp) {}

bool write_rows(std::FILE* file, const cv::Mat& frame, PngError& error) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, png_write_failed, png_write_quiet);
  if (!png) {
    std::snprintf(error.message, sizeof error.message, "libpng could not start (out of memory)");
    return false;
  }
  png_infop info = png_create_info_struct(png);
  const int colour_type = frame.channels() == 1   ? PNG_COLOR_TYPE_GRAY
                          : frame.channels() == 3 ? PNG_COLOR_TYPE_RGB
                                                  : PNG_COLOR_TYPE_RGB_ALPHA;
  bool ok = false;
  if (info && setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, file);
    png_set_IHDR(png, info, static_cast<png_uint_32>(frame.cols), static_cast<png_uint_32>(frame.rows),
                 frame.depth() == CV_16U ? 16 : 8, colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
    png_set_compression_level(png, Z_NO_COMPRESSION);
    png_write_info(png, info);
    // PNG holds 16-bit samples big-endian and colour as RGB; OpenCV holds
    // them in the host's order and as BGR.
    if (frame.depth() == CV_16U && std::endian::native == std::endian::little) png_set_swap(png);
    if (frame.channels() > 1) png_set_bgr(png);
    for (int y = 0; y < frame.rows; ++y) png_write_row(png, frame.ptr(y));
    png_write_end(png, info);
    ok = true;
  }
  png_destroy_write_struct(&png, info ? &info : nullptr);
  return ok;
}

struct FileCloser {
  void operator()(std::FILE* file) const { std::fclose(file); }
};

}  // namespace

void write_frame_png(const std::filesystem::path& path, const cv::Mat& frame) {
  const int channels = frame.channels();
  if (frame.empty()) throw std::invalid_argument(path.string() + ": the frame is empty");
  if ((frame.depth() != CV_8U && frame.depth() != CV_16U) || (channels != 1 && channels != 3 && channels != 4)) {
    throw std::invalid_argument(
        fmt::format("{}: a frame is stored as an 8- or 16-bit PNG of 1, 3 or 4 channels; this one is {}", path.string(),
                    cv::typeToString(frame.type())));
  }
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
  if (!file)
    throw std::runtime_error(fmt::format("{}: cannot be opened for writing: {}", path.string(), std::strerror(errno)));
  PngError error{};
  if (!write_rows(file.get(), frame, error)) throw std::runtime_error(path.string() + ": " + error.message);
  // A full disk may show only when the last buffer is flushed.
  if (std::fclose(file.release()) != 0) {
    throw std::runtime_error(fmt::format("{}: cannot be written: {}", path.string(), std::strerror(errno)));
  }
}

}  // namespace bosfuse::acquisition
