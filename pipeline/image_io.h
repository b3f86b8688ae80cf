#pragma once
// Reading images for the pipeline and the command line: file problems become
// messages that name the file, so `bosfuse evaluate` can say which input was
// unreadable instead of "empty image".

#include <opencv2/core.hpp>
#include <string>

namespace bosfuse::pipeline {

// Any depth and channel count OpenCV reads (8/16-bit grey or colour).
cv::Mat read_image(const std::string& path, const std::string& role);

}  // namespace bosfuse::pipeline
