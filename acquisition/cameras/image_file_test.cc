#include "acquisition/cameras/image_file.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdint>
#include <cstdlib>
#include <new>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/support/forged_image.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"

namespace bosfuse::acquisition {
namespace {

TEST(ImageFile, TheDeclaredSizeComesFromTheHeaderOfEachFormat) {
  const cv::Mat image = testing::textured_frame(1, CV_8U, {40, 30});
  for (const char* extension : {".png", ".jpg", ".tif", ".bmp"}) {
    const auto size = declared_image_size(testing::encoded(image, extension));
    ASSERT_TRUE(size) << extension;
    EXPECT_EQ(size->width_px, 40) << extension;
    EXPECT_EQ(size->height_px, 30) << extension;
  }
  const auto forged = declared_image_size(testing::png_declaring(20000, 20000));
  ASSERT_TRUE(forged);
  EXPECT_EQ(forged->width_px, 20000);
  EXPECT_FALSE(declared_image_size(std::vector<std::uint8_t>{'n', 'o', 't'}));
}

// Found by fuzzing: a 56-byte BMP declaring 524288x2048 px (2^30 pixels,
// just inside OpenCV's own limit) made it allocate 3 GB. Its header now
// refuses it.
TEST(ImageFile, AHugeBmpIsRefusedByItsHeader) {
  std::vector<std::uint8_t> bmp = {'B', 'M', 0xf6, 0, 0, 0,    0, 0xa1, 0,    0, 0x36, 0, 0, 0,    0x28,
                                   0,   0,   0,    0, 0, 0x08, 0, 0,    0x08, 0, 0,    1, 0, 0x18, 0};
  bmp.resize(56, 0);
  const auto size = declared_image_size(bmp);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width_px, 524288);
  EXPECT_EQ(size->height_px, 2048);
  EXPECT_THROW(decode_image(bmp, "bomb.bmp"), ImageTooLarge);
}

// The 388 KB PNG of 20000x20000 zeros once took 7.5 GB and 134 s; its
// header alone now refuses it, with the file's name and declared size.
TEST(ImageFile, AHugeDeclaredSizeIsRefusedBeforeDecoding) {
  try {
    decode_image(testing::png_declaring(20000, 20000), "bomb.png");
    FAIL() << "decoded";
  } catch (const ImageTooLarge& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bomb.png: the image declares 20000x20000 px (400.0 megapixels), over", 0),
              0u)
        << e.what();
  }
  EXPECT_THROW(decode_image(testing::png_declaring(30001, 1), "wide.png"), ImageTooLarge) << "a side over 30000 px";
  EXPECT_THROW(decode_image(testing::png_declaring(0x7fffffff, 0x7fffffff), "max.png"), ImageTooLarge);
}

TEST(ImageFile, TheLimitsApplyToEveryFormatWithAHeaderReader) {
  const cv::Mat image = testing::textured_frame(2, CV_16U, {40, 30});
  const ImageLimits small{1000, 30000};
  for (const char* extension : {".png", ".tif"}) {
    const auto bytes = testing::encoded(image, extension);
    EXPECT_THROW(decode_image(bytes, extension, small), ImageTooLarge) << extension;
    const cv::Mat decoded = decode_image(bytes, extension);
    ASSERT_EQ(decoded.type(), CV_16U) << extension;
    EXPECT_EQ(cv::norm(decoded, image, cv::NORM_INF), 0.0) << extension;
  }
  EXPECT_THROW(decode_image(testing::encoded(testing::textured_frame(3), ".jpg"), "j", {100, 30000}), ImageTooLarge);
  EXPECT_THROW(decode_image(testing::encoded(image, ".png"), "side", {100'000, 39}), ImageTooLarge);
}

TEST(ImageFile, TheLimitsComeFromTheEnvironment) {
  ::setenv("BOSFUSE_MAX_IMAGE_PIXELS", "1000", 1);
  ::setenv("BOSFUSE_MAX_IMAGE_SIDE_PX", "50", 1);
  ::setenv("BOSFUSE_MAX_IMAGE_METADATA_MB", "3", 1);
  const ImageLimits limits = ImageLimits::from_environment();
  ::setenv("BOSFUSE_MAX_IMAGE_PIXELS", "lots", 1);
  EXPECT_THROW(ImageLimits::from_environment(), std::invalid_argument);
  ::setenv("BOSFUSE_MAX_IMAGE_PIXELS", "1000", 1);
  ::setenv("BOSFUSE_MAX_IMAGE_METADATA_MB", "-1", 1);
  EXPECT_THROW(ImageLimits::from_environment(), std::invalid_argument);
  ::unsetenv("BOSFUSE_MAX_IMAGE_PIXELS");
  ::unsetenv("BOSFUSE_MAX_IMAGE_SIDE_PX");
  ::unsetenv("BOSFUSE_MAX_IMAGE_METADATA_MB");
  EXPECT_EQ(limits.max_pixels, 1000);
  EXPECT_EQ(limits.max_side_px, 50);
  EXPECT_EQ(limits.max_metadata_bytes, 3'000'000);
  const ImageLimits defaults = ImageLimits::from_environment();
  EXPECT_EQ(defaults.max_pixels, 100'000'000);
  EXPECT_EQ(defaults.max_side_px, 30'000);
  EXPECT_EQ(defaults.max_metadata_bytes, 64'000'000);
}

// Found by fuzzing: Debian's OpenCV hands a DICOM header to GDCM, which
// allocated 1.7 GB for 166 bytes. Only the formats bosfuse reads are decoded.
TEST(ImageFile, OnlyTheFormatsBosfuseReadsAreDecoded) {
  std::vector<std::uint8_t> dicom(128, 0);
  for (char c : std::string("DICM\x02\x00\x10\x00UI")) dicom.push_back(static_cast<std::uint8_t>(c));
  dicom.resize(400, 0xff);
  EXPECT_TRUE(decode_image(dicom, "forged.dcm").empty());
  const cv::Mat image(7, 5, CV_8U, cv::Scalar(90));
  for (const char* extension : {".png", ".bmp", ".pgm", ".tif", ".jpg"}) {
    std::vector<std::uint8_t> bytes;
    ASSERT_TRUE(cv::imencode(extension, image, bytes)) << extension;
    const cv::Mat decoded = decode_image(bytes, std::string("frame") + extension);
    EXPECT_EQ(decoded.size(), image.size()) << extension;
  }
}

// Found by fuzzing: "P5" then no space is no PNM to OpenCV, which went on to
// its DICOM decoder for the "DICM" at offset 128, and GDCM's assert aborted
// the process. Bytes are taken as PNM only as OpenCV takes them.
TEST(ImageFile, BytesOpenCvTakesForNoFormatOfOursAreNotDecoded) {
  std::vector<std::uint8_t> bytes = {'P', '5', 0xb3, 0, 1, 0, 0, 0};
  bytes.resize(128, 0);
  for (char c : std::string("DICM\x02\x00\x00\xfc")) bytes.push_back(static_cast<std::uint8_t>(c));
  bytes.resize(180, 0x20);
  EXPECT_FALSE(declared_image_size(bytes));
  EXPECT_TRUE(decode_image(bytes, "forged.pgm").empty());
}

// A PNM of `header` and 64 bytes of pixels declares width × height and is
// refused by the limits before decoding.
void expect_pnm_refused(const std::string& header, std::int64_t width_px, std::int64_t height_px) {
  SCOPED_TRACE(header);
  std::vector<std::uint8_t> pnm(header.begin(), header.end());
  pnm.resize(pnm.size() + 64, 0);
  const auto size = declared_image_size(pnm);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->width_px, width_px);
  EXPECT_EQ(size->height_px, height_px);
  EXPECT_THROW(decode_image(pnm, "bomb.pnm"), ImageTooLarge);
}

TEST(ImageFile, AHugePnmIsRefusedByItsHeader) {
  expect_pnm_refused("P5\n# a comment 99999 99999\n40000 # another\n 30000\n65535\n", 40000, 30000);
}

// Found by fuzzing: leading zeros made the header's numbers longer than the
// ten digits once read, so "0000000000" was taken for the width and the real
// width for the height; OpenCV then allocated 2.3 GB for 27565x27568 px.
TEST(ImageFile, EveryDigitOfAPnmSizeCounts) {
  expect_pnm_refused("P6 0000000000" "27565 27568 255\n", 27565, 27568);

  const std::string endless = "P5 " + std::string(40, '9') + " 1 255\n";
  const auto saturated = declared_image_size(std::vector<std::uint8_t>(endless.begin(), endless.end()));
  ASSERT_TRUE(saturated);
  EXPECT_GT(saturated->width_px, ImageLimits{}.max_side_px) << "a 40-digit width stays over every limit";
}

TEST(ImageFile, MissingOrUndecodableFilesAreEmpty) {
  testing::TempDir dir;
  EXPECT_TRUE(read_image_file(dir / "none.png").empty());
  EXPECT_TRUE(read_image_file(dir.path()).empty()) << "a folder";
  testing::write_file(dir / "junk.png", {'j', 'u', 'n', 'k'});
  EXPECT_TRUE(read_image_file(dir / "junk.png").empty());
  testing::write_file(dir / "ok.png", testing::encoded(testing::textured_frame(4), ".png"));
  EXPECT_EQ(read_image_file(dir / "ok.png").size(), cv::Size(64, 48));
}

// The most this process has held in memory so far, in bytes.
std::int64_t peak_memory_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::int64_t>(usage.ru_maxrss) * 1024;
}

constexpr std::uint64_t kPaddedBytes = 1'900'000'000;

// The probe's file: a real 256x256 image padded to 1.9 GB (sparse: no disk
// is used), once read whole (2.03 GB and 8.9 s for the PNG). Now the file's
// size is held against what 256x256 px can need in each format, from the
// header alone: refused with the file's name, its size and the limit, and
// the process's memory does not grow by anything like the padding.
TEST(ImageFile, APaddedImageIsRefusedBeforeItIsReadWhole) {
  testing::TempDir dir;
  const cv::Mat image = testing::textured_frame(5, CV_8U, {256, 256});
  const std::int64_t peak_before = peak_memory_bytes();
  for (const char* extension : {".png", ".jpg", ".tif", ".bmp", ".pgm"}) {
    const auto path = dir / (std::string("padded") + extension);
    testing::write_padded(path, testing::encoded(image, extension), kPaddedBytes);
    try {
      read_image_file(path);
      FAIL() << extension << " was decoded";
    } catch (const ImageTooLarge& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.rfind(path.string() + ": the file is 1900000000 bytes (1900.0 MB), more than a 256x256 px ", 0),
                0u)
          << message;
      EXPECT_NE(message.find("can need (at most "), std::string::npos) << message;
      EXPECT_NE(message.find("BOSFUSE_MAX_IMAGE_METADATA_MB); not read"), std::string::npos) << message;
    }
    EXPECT_THROW(read_image_bytes(path), ImageTooLarge) << extension;
  }
  EXPECT_LT(peak_memory_bytes() - peak_before, 200'000'000) << "the padding was read";
}

// The limit on a file's size is what its header's pixels can need, as
// stated: twice the deepest pixel of the format, plus the metadata
// allowance. A file of exactly that size is decoded, one byte more is not,
// from memory as from a file.
TEST(ImageFile, AFileIsAllowedTwiceItsDeepestPixelsPlusTheMetadataAllowance) {
  testing::TempDir dir;
  const ImageLimits limits{100'000, 1000, 50'000};
  const cv::Mat image = testing::textured_frame(6, CV_8U, {64, 48});
  const struct {
    const char* extension;
    ImageFormat format;
    int deepest_bytes;
  } formats[] = {{".png", ImageFormat::kPng, 8},
                 {".jpg", ImageFormat::kJpeg, 4},
                 {".tif", ImageFormat::kTiff, 32},
                 {".bmp", ImageFormat::kBmp, 4},
                 {".pgm", ImageFormat::kPnm, 18}};
  for (const auto& f : formats) {
    SCOPED_TRACE(f.extension);
    const std::int64_t most = limits.max_file_bytes(f.format, {64, 48});
    EXPECT_EQ(most, 2 * 64 * 48 * f.deepest_bytes + 50'000);
    std::vector<std::uint8_t> bytes = testing::encoded(image, f.extension);
    bytes.resize(static_cast<std::size_t>(most), 0);
    EXPECT_EQ(decode_image(bytes, "exact", limits).size(), image.size());
    testing::write_padded(dir / "exact", bytes, bytes.size());
    EXPECT_EQ(read_image_file(dir / "exact", limits).size(), image.size());
    bytes.push_back(0);
    EXPECT_THROW(decode_image(bytes, "over", limits), ImageTooLarge);
    testing::write_padded(dir / "over", bytes, bytes.size());
    EXPECT_THROW(read_image_file(dir / "over", limits), ImageTooLarge);
  }
  EXPECT_EQ(limits.max_file_bytes(), 2 * 100'000 * 32 + 50'000) << "the deepest format at the pixel limit";
  EXPECT_EQ(ImageLimits{}.max_file_bytes(), 6'464'000'000);
}

// Before its header is read: a file larger than any image within the limits
// can need is refused from its size alone, whatever it holds.
TEST(ImageFile, AFileLargerThanAnyImageWithinTheLimitsIsRefusedFromItsSize) {
  testing::TempDir dir;
  testing::write_padded(dir / "huge.png", {'j', 'u', 'n', 'k'}, 7'000'000'000);
  try {
    read_image_file(dir / "huge.png");
    FAIL() << "read";
  } catch (const ImageTooLarge& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "huge.png").string() +
                  ": the file is 7000000000 bytes (7000.0 MB), more than any image within the limits can need "
                  "(6464000000 bytes; BOSFUSE_MAX_IMAGE_PIXELS, BOSFUSE_MAX_IMAGE_METADATA_MB); not read");
  }
}

// Metadata before the pixels is read by the format's library only up to the
// allowance: a PNG with a 1.9 GB chunk before its image data is refused
// without reading the chunk through.
TEST(ImageFile, AHeaderLongerThanTheMetadataAllowanceIsRefused) {
  testing::TempDir dir;
  std::vector<std::uint8_t> png = testing::encoded(testing::textured_frame(7), ".png");
  // After the signature and IHDR (8 + 25 bytes): a private chunk "prVt" claiming 1.9 GB.
  const std::uint32_t length = 1'900'000'000;
  const std::vector<std::uint8_t> chunk = {static_cast<std::uint8_t>(length >> 24),
                                           static_cast<std::uint8_t>(length >> 16),
                                           static_cast<std::uint8_t>(length >> 8),
                                           static_cast<std::uint8_t>(length),
                                           'p',
                                           'r',
                                           'V',
                                           't'};
  png.insert(png.begin() + 33, chunk.begin(), chunk.end());
  testing::write_padded(dir / "chunk.png", png, 1'950'000'000);
  const ImageLimits limits{100'000'000, 30'000, 1'000'000};
  try {
    read_image_file(dir / "chunk.png", limits);
    FAIL() << "read";
  } catch (const ImageUnreadable& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "chunk.png").string() +
                                         ": not a readable PNG: its chunks before the image data are longer than "
                                         "allowed")
        << e.what();
  }
}

// Half an image, and one missing only its last byte: refused in every
// format, naming the file, with the format library's own word where it has
// one. OpenCV alone decodes half a JPEG, grey where the data ran out.
TEST(ImageFile, ATruncatedImageIsRefusedNamingTheFile) {
  testing::TempDir dir;
  const cv::Mat image = testing::textured_frame(8, CV_8U, {320, 240});
  for (const char* extension : {".jpg", ".png", ".tif", ".bmp", ".pgm"}) {
    const std::vector<std::uint8_t> whole = testing::encoded(image, extension);
    for (const std::size_t kept : {whole.size() / 2, whole.size() - 1}) {
      SCOPED_TRACE(std::string(extension) + " of " + std::to_string(kept) + " bytes");
      const auto path = dir / (std::string("cut") + extension);
      testing::write_file(path, std::vector<std::uint8_t>(whole.begin(), whole.begin() + kept));
      try {
        read_image_file(path);
        FAIL() << "decoded";
      } catch (const ImageUnreadable& e) {
        EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << e.what();
        if (std::string(extension) == ".jpg") {
          EXPECT_NE(std::string(e.what()).find("the JPEG's image data is incomplete or damaged (libjpeg: "),
                    std::string::npos)
              << e.what();
        }
      }
    }
  }
  const std::vector<std::uint8_t> jpeg = testing::encoded(image, ".jpg");
  const std::vector<std::uint8_t> half(jpeg.begin(), jpeg.begin() + jpeg.size() / 2);
  EXPECT_FALSE(cv::imdecode(half, cv::IMREAD_UNCHANGED).empty()) << "what OpenCV makes of half a JPEG";
  EXPECT_EQ(jpeg_data_problem(half), "Premature end of JPEG file");
  EXPECT_EQ(jpeg_data_problem(jpeg), "");
}

// Not cut short but damaged: an end-of-image marker in the middle of the
// data, where OpenCV decodes the rest as grey. libjpeg says the data is
// corrupt, and the image is refused.
TEST(ImageFile, AJpegWhoseDataIsDamagedIsRefused) {
  std::vector<std::uint8_t> jpeg = testing::encoded(testing::textured_frame(11, CV_8U, {320, 240}), ".jpg");
  const std::size_t middle = jpeg.size() / 2;
  jpeg[middle] = 0xFF;
  jpeg[middle + 1] = 0xD9;
  EXPECT_FALSE(cv::imdecode(jpeg, cv::IMREAD_UNCHANGED).empty()) << "what OpenCV makes of it";
  try {
    decode_image(jpeg, "damaged.jpg");
    FAIL() << "decoded";
  } catch (const ImageUnreadable& e) {
    EXPECT_EQ(
        std::string(e.what()).rfind("damaged.jpg: the JPEG's image data is incomplete or damaged (libjpeg: Corrupt "
                                    "JPEG data",
                                    0),
        0u)
        << e.what();
  }
}

// A TIFF's directory can come before its pixels: cut short, its header
// still reads, and its strips run past the end of the file.
TEST(ImageFile, ATiffWhoseStripsRunPastItsEndIsTruncated) {
  const cv::Mat image = testing::textured_frame(9, CV_8U, {40, 30});
  std::vector<std::uint8_t> tiff = testing::tiff_with_directory_first(image);
  const cv::Mat whole = decode_image(tiff, "first.tif");
  ASSERT_EQ(whole.size(), image.size());
  EXPECT_EQ(cv::norm(whole, image, cv::NORM_INF), 0.0);
  const std::size_t size = tiff.size();
  tiff.resize(size - 100);
  try {
    decode_image(tiff, "cut.tif");
    FAIL() << "decoded";
  } catch (const ImageUnreadable& e) {
    EXPECT_EQ(std::string(e.what()), "cut.tif: truncated: the TIFF's image data runs to byte " + std::to_string(size) +
                                         ", the file has " + std::to_string(size - 100) + " bytes");
  }
}

// OpenCV's allocator, which every decoded image comes from, refusing what
// is larger than `most_bytes` as an exhausted heap does.
class RefusingAllocator : public cv::MatAllocator {
 public:
  explicit RefusingAllocator(std::size_t most_bytes) : most_bytes_(most_bytes) { cv::Mat::setDefaultAllocator(this); }
  ~RefusingAllocator() override { cv::Mat::setDefaultAllocator(previous_); }
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, std::size_t* step, cv::AccessFlag flags,
                         cv::UMatUsageFlags usage) const override {
    std::size_t bytes = CV_ELEM_SIZE(type);
    for (int i = 0; i < dims; ++i) bytes *= static_cast<std::size_t>(sizes[i]);
    if (!data && bytes > most_bytes_) throw std::bad_alloc();
    return standard_->allocate(dims, sizes, type, data, step, flags, usage);
  }
  bool allocate(cv::UMatData* data, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override {
    return standard_->allocate(data, flags, usage);
  }
  void deallocate(cv::UMatData* data) const override { standard_->deallocate(data); }

 private:
  std::size_t most_bytes_;
  cv::MatAllocator* standard_ = cv::Mat::getStdAllocator();
  cv::MatAllocator* previous_ = cv::Mat::getDefaultAllocator();
};

// Under `ulimit -v` the probe met a bare std::bad_alloc. Running out of
// memory while decoding is an error that names the file, like any other.
TEST(ImageFile, RunningOutOfMemoryWhileDecodingIsAnErrorNamingTheFile) {
  testing::TempDir dir;
  for (const auto& [extension, format] : {std::pair{".png", "PNG"}, {".jpg", "JPEG"}, {".tif", "TIFF"}}) {
    const auto path = dir / (std::string("frame") + extension);
    testing::write_file(path, testing::encoded(testing::textured_frame(10, CV_8U, {320, 240}), extension));
    const RefusingAllocator refusing(10'000);
    try {
      read_image_file(path);
      FAIL() << extension << " decoded";
    } catch (const ImageUnreadable& e) {
      EXPECT_EQ(std::string(e.what()), path.string() + ": out of memory decoding its 320x240 px " + format + " image");
    }
  }
  EXPECT_EQ(read_image_file(dir / "frame.png").size(), cv::Size(320, 240)) << "with memory again";
}

}  // namespace
}  // namespace bosfuse::acquisition
