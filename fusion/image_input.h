#pragma once
// Input checks shared by every evaluator: an image pair (and an optional
// mask) is turned into single-channel float images scaled to [0, 1] of full
// scale, whatever the camera delivered (8- or 16-bit, grey or colour). A
// problem a user can fix — an empty image, sizes that differ, a window larger
// than the image — raises std::invalid_argument whose message names it.
// Colour images are accepted and converted to grey with a warning (a
// string for the caller to log: fusion/ logs nothing), since a colour camera
// is a legitimate (if wasteful) BOS camera.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace bosfuse::fusion {

// `name` labels the image in messages ("reference", "measurement", a path).
// Returns CV_32FC1 in [0, 1]; 8-bit divides by 255, 16-bit by 65535, float
// input is taken as already scaled.
// `warnings`: where the warning that a colour image was converted goes;
// nullptr converts it silently (the caller warned once).
// The conversion is OpenCV's (cv::Mat::convertTo, cv::cvtColor), which is
// vectorised already (OpenCV's universal intrinsics); non-finite pixels,
// which only float input can hold, become 0.
cv::Mat to_grey_unit_float(const cv::Mat& image, const std::string& name,
                           std::vector<std::string>* warnings = nullptr);

// Creates `image` as rows×cols of `type` (kept when it has that shape
// already) and, when it is new and large, asks the kernel to back it with
// 2 MB pages: a 16 MP float image is then 32 page faults on first touch
// rather than 16,000, which in a virtual machine cost tens of milliseconds
// per image, and its windows do not miss the TLB. Only advice: where the
// kernel has no transparent huge pages the buffer is an ordinary one.
void create_large_image(cv::Mat& image, int rows, int cols, int type);

// The same into `out`, whose buffer is reused when it has the image's size
// already (a frame after frame evaluator converts every frame into one
// buffer rather than page-faulting a fresh 64 MB one). `out` must not share
// pixels with `image`.
void to_grey_unit_float(const cv::Mat& image, const std::string& name, std::vector<std::string>* warnings,
                        cv::Mat& out);

// "reference: colour image (3 channels) converted to grey": what an image
// `name` of `channels` channels warns of when converted.
std::string colour_conversion_warning(const std::string& name, int channels);

// The value of full scale of an image depth: 255 for 8-bit, 65535 for
// 16-bit, 1 for float (taken as scaled already).
double full_scale(int depth);

// Throws std::invalid_argument naming the problem: empty images, sizes that
// differ, or a mask whose size is not the images'.
void check_image_pair(const cv::Mat& reference, const cv::Mat& measurement, const cv::Mat& mask = {});

// Throws when a window of `window_px` does not fit in `image_size`.
void check_window_fits(int window_px, cv::Size image_size);

// A mask as CV_8U where non-zero marks excluded pixels; empty stays empty.
cv::Mat to_exclusion_mask(const cv::Mat& mask);

}  // namespace bosfuse::fusion
