#pragma once
// How bosfuse stores a camera frame: a PNG whose rows are not filtered and
// whose deflate stream is not compressed (stored blocks). A BOS frame is a
// random-dot pattern under sensor noise, which deflate cannot shrink: a
// 16-bit 16 MP frame is 31.5 MB as OpenCV writes a PNG by default and
// 32.2 MB stored, but it is written in ~90 ms instead of ~350 ms, and every
// command that reads it decodes it in ~40 ms instead of ~170 ms (libpng's
// unfiltering and zlib's inflate; BM_FramePng16MP in docs/BENCHMARKS.md). The
// file is an ordinary PNG that any reader opens; bosfuse reads it, like any
// other image, through acquisition/cameras/image_file.h.
//
// Use write_frame_png wherever a run's frames are written (the recorder,
// and benchmarks and tools that stand in for it), so that they decode as
// recorded runs do.

#include <filesystem>
#include <opencv2/core.hpp>

namespace bosfuse::acquisition {

// Writes `frame` (8- or 16-bit; grey, BGR or BGRA, as OpenCV holds colour)
// to `path` losslessly. Throws std::invalid_argument for any other depth or
// channel count (PNG cannot hold it without loss), std::runtime_error naming
// the path when the file cannot be written.
void write_frame_png(const std::filesystem::path& path, const cv::Mat& frame);

}  // namespace bosfuse::acquisition
