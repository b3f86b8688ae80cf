// Image loading. The input is an image file's bytes (seeds: tiny PNG, JPEG,
// TIFF, PGM and BMP images at 8 and 16 bits, one JPEG with EXIF capture
// time). They are loaded the ways bosfuse loads images: written to a file
// and read with pipeline::read_image() (pipeline/image_io.cc, what `bosfuse evaluate`
// and `quality` use; compiled into this target since app/ is no library),
// decoded from memory with cv::imdecode(IMREAD_UNCHANGED) as the watched-
// folder camera does, and searched for an EXIF capture time with
// acquisition::exif_capture_time(). OPENCV_IO_MAX_IMAGE_PIXELS caps decoded
// images at 4 Mpixel (set in LLVMFuzzerInitialize) so a forged header cannot
// run the fuzzer out of memory; the same cap belongs in bosfuse's loader.
// Invariants: read_image returns a non-empty image or throws a
// std::exception whose message names the file; it never returns a JPEG in
// which libjpeg finds the image data incomplete or damaged (OpenCV alone
// decodes half a JPEG with a warning); it agrees with cv::imdecode
// on the same bytes (when both decode them, the same size, depth and
// channels); exif_capture_time returns nothing or a time whose seconds
// fit in int64 nanoseconds (never undefined behaviour on a forged date).

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "acquisition/cameras/exif_time.h"
#include "acquisition/cameras/image_header.h"
#include "fuzz/fuzz_support.h"
#include "pipeline/image_io.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // Read by OpenCV once, at the first decode; must be set before it.
  setenv("OPENCV_IO_MAX_IMAGE_PIXELS", "4194304", 1);
  setenv("OPENCV_IO_MAX_IMAGE_WIDTH", "65536", 1);
  setenv("OPENCV_IO_MAX_IMAGE_HEIGHT", "65536", 1);
  setenv("OPENCV_IO_ENABLE_OPENEXR", "0", 1);
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static bosfuse::fuzz::ScratchDir scratch;  // removed when the fuzzer exits
  const std::string path = (scratch.path() / "frame.img").string();
  bosfuse::fuzz::write_file(path, data, size);

  cv::Mat from_file;
  bool file_ok = false;
  try {
    from_file = bosfuse::pipeline::read_image(path, "image");
    FUZZ_CHECK(!from_file.empty());
    file_ok = true;
  } catch (const std::exception& e) {
    if (std::string(e.what()).find(path) == std::string::npos) std::fprintf(stderr, "message: %s\n", e.what());
    FUZZ_CHECK(std::string(e.what()).find(path) != std::string::npos);
  }

  // Only what bosfuse decoded is compared with OpenCV's own decoder: fed
  // anything, OpenCV would also hand DICOM and GDAL formats to decoders that
  // allocate gigabytes before its limits apply (bosfuse refuses them).
  if (file_ok && size >= 3 && data[0] == 0xff && data[1] == 0xd8 && data[2] == 0xff) {
    FUZZ_CHECK(bosfuse::acquisition::jpeg_data_problem(std::span(data, size)).empty());
  }
  if (file_ok) {
    cv::Mat from_memory;
    try {
      from_memory = cv::imdecode(std::vector<std::uint8_t>(data, data + size), cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
      // OpenCV throws for some malformed files instead of returning an empty image
    }
    // OpenCV 4.6 itself does not always agree between file and memory on a
    // damaged JPEG (one decodes, the other gives up), so only images both
    // decode are compared.
    if (!from_memory.empty()) {
      FUZZ_CHECK(from_file.size() == from_memory.size());
      FUZZ_CHECK(from_file.type() == from_memory.type());
    }
  }

  (void)bosfuse::acquisition::exif_capture_time(std::span(data, size));
  return 0;
}
