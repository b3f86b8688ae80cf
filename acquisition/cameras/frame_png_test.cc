#include "acquisition/cameras/frame_png.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "acquisition/cameras/image_file.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_images.h"
#include "tests/support/file_bytes.h"

namespace bosfuse::acquisition {
namespace {

std::uint32_t big_endian(const std::uint8_t* p) {
  return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3];
}

// The concatenated IDAT chunks of a PNG file: its zlib stream.
std::vector<std::uint8_t> zlib_stream(const std::vector<std::uint8_t>& png) {
  std::vector<std::uint8_t> stream;
  for (std::size_t at = 8; at + 12 <= png.size();) {
    const std::uint32_t length = big_endian(&png[at]);
    const std::string type(png.begin() + static_cast<std::ptrdiff_t>(at) + 4,
                           png.begin() + static_cast<std::ptrdiff_t>(at) + 8);
    if (type == "IDAT") stream.insert(stream.end(), &png[at + 8], &png[at + 8] + length);
    at += 12 + length;
  }
  return stream;
}

TEST(FramePng, EveryFrameTypeReadsBackBitForBitInItsChannelOrder) {
  testing::TempDir dir;
  cv::Mat wide = testing::textured_frame(7, CV_16U, {90, 40});
  std::vector<cv::Mat> frames = {testing::textured_frame(1, CV_8U), testing::textured_frame(2, CV_16U),
                                 wide(cv::Rect(5, 3, 61, 29))};  // a view: rows not contiguous
  for (int type : {CV_8UC3, CV_16UC3, CV_8UC4, CV_16UC4}) {
    cv::Mat colour(33, 47, type);
    cv::randu(colour, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);  // channels differ: a swap would show
    frames.push_back(colour);
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto path = dir.path() / ("frame" + std::to_string(i) + ".png");
    write_frame_png(path, frames[i]);
    for (const cv::Mat& read : {read_image_file(path), cv::imread(path.string(), cv::IMREAD_UNCHANGED)}) {
      ASSERT_EQ(read.type(), frames[i].type()) << cv::typeToString(frames[i].type());
      ASSERT_EQ(read.size(), frames[i].size());
      EXPECT_EQ(cv::norm(read, frames[i], cv::NORM_INF), 0.0) << cv::typeToString(frames[i].type());
    }
  }
}

TEST(FramePng, RowsAreUnfilteredAndTheDeflateStreamIsNotCompressed) {
  testing::TempDir dir;
  // A smooth ramp: deflate would shrink it to a fraction, and libpng's
  // adaptive filters would choose Sub or Up for its rows.
  cv::Mat ramp(64, 200, CV_16U);
  for (int y = 0; y < ramp.rows; ++y) {
    for (int x = 0; x < ramp.cols; ++x) ramp.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(100 * x + y);
  }
  const auto path = dir.path() / "ramp.png";
  write_frame_png(path, ramp);
  const std::vector<std::uint8_t> stream = zlib_stream(testing::file_byte_vector(path));
  const std::size_t row_bytes = 1 + 2 * static_cast<std::size_t>(ramp.cols);  // filter byte + samples
  const std::size_t raw_bytes = row_bytes * static_cast<std::size_t>(ramp.rows);
  EXPECT_GT(stream.size(), raw_bytes) << "stored blocks hold every byte plus their headers";
  std::vector<std::uint8_t> raw(raw_bytes);
  uLongf raw_length = static_cast<uLongf>(raw.size());
  ASSERT_EQ(uncompress(raw.data(), &raw_length, stream.data(), static_cast<uLong>(stream.size())), Z_OK);
  ASSERT_EQ(raw_length, raw_bytes);
  for (int y = 0; y < ramp.rows; ++y) EXPECT_EQ(raw[static_cast<std::size_t>(y) * row_bytes], 0) << "row " << y;
}

TEST(FramePng, WhatPngCannotHoldIsRefusedByTypeBeforeAnyFileExists) {
  testing::TempDir dir;
  const auto path = dir.path() / "frame.png";
  for (int type : {CV_32FC1, CV_16SC1, CV_8UC2}) {
    try {
      write_frame_png(path, cv::Mat(8, 8, type, cv::Scalar::all(1)));
      ADD_FAILURE() << cv::typeToString(type) << " was written";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(cv::typeToString(type)), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(path));
  }
  EXPECT_THROW(write_frame_png(path, cv::Mat()), std::invalid_argument);
}

TEST(FramePng, AFileThatCannotBeWrittenIsNamed) {
  testing::TempDir dir;
  const auto missing = dir.path() / "no-such-folder" / "frame.png";
  try {
    write_frame_png(missing, testing::textured_frame(1));
    ADD_FAILURE() << "written into a missing folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
  // /dev/full opens, then fails every write: a full disk.
  EXPECT_THROW(write_frame_png("/dev/full", testing::textured_frame(1, CV_16U, {640, 480})), std::runtime_error);
}

}  // namespace
}  // namespace bosfuse::acquisition
