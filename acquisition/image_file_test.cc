#include "acquisition/image_file.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
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
  const ImageLimits limits = ImageLimits::from_environment();
  ::setenv("BOSFUSE_MAX_IMAGE_PIXELS", "lots", 1);
  EXPECT_THROW(ImageLimits::from_environment(), std::invalid_argument);
  ::unsetenv("BOSFUSE_MAX_IMAGE_PIXELS");
  ::unsetenv("BOSFUSE_MAX_IMAGE_SIDE_PX");
  EXPECT_EQ(limits.max_pixels, 1000);
  EXPECT_EQ(limits.max_side_px, 50);
  const ImageLimits defaults = ImageLimits::from_environment();
  EXPECT_EQ(defaults.max_pixels, 100'000'000);
  EXPECT_EQ(defaults.max_side_px, 30'000);
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

}  // namespace
}  // namespace bosfuse::acquisition
