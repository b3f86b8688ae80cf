#pragma once
// Dense optical flow as a second displacement method, behind the same
// interface as cross-correlation: OpenCV computes a flow vector per pixel
// (DIS, Farneback, or TV-L1 where opencv_contrib's optflow module is
// available), and the flow is averaged over each interrogation window of the
// same grid the cross-correlation uses, so the two can be compared vector by
// vector. Use it to cross-check cross-correlation or where windows are too
// coarse; expect it to be less accurate at the 0.01 px level BOS needs, since
// the images are reduced to 8 bits and the methods regularise the field.
//
// Flow from reference to measurement is exactly the DESIGN.md displacement:
// reference(x, y) ≈ measurement(x + u, y + v).

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fusion/evaluation.h"

namespace bosfuse::fusion {

enum class FlowAlgorithm { kDis, kFarneback, kTvl1 };

// The one name table of the algorithms ("dis", "farneback", "tvl1"), used by
// the commands and the stored settings; the names in the enum's order.
std::string to_string(FlowAlgorithm algorithm);
std::optional<FlowAlgorithm> parse_flow_algorithm(std::string_view name);
std::vector<std::string> flow_algorithm_names();
bool flow_algorithm_available(FlowAlgorithm algorithm);

// OpenCV's DIS presets (DISOpticalFlow::PRESET_*), each run down to full
// resolution here (BOS shifts are sub-pixel). Medium, the default, adds a
// variational refinement at every scale, whose buffers bring OpenCV's own
// memory to about 215 bytes a pixel (3.5 GB for a 16 MP pair); ultrafast
// skips it and needs about 45 (OpenCV 4.6, memory_budget.h) and about a
// third of the time. Neither is better everywhere: medium is the closer on a uniform
// shift (optical_flow_test), ultrafast on the 16 MP bump of bos_bench's
// FullFrame16MPMethods (0.011 against 0.014 px RMS).
enum class DisPreset { kUltrafast, kFast, kMedium };

// The one name table of the presets ("ultrafast", "fast", "medium"), likewise.
std::string to_string(DisPreset preset);
std::optional<DisPreset> parse_dis_preset(std::string_view name);
std::vector<std::string> dis_preset_names();

struct FlowOptions {
  FlowAlgorithm algorithm = FlowAlgorithm::kDis;
  DisPreset dis_preset = DisPreset::kMedium;  // DIS only
  int window_px = 16;                         // averaging window, same grid as cross-correlation
  int step_px = 8;
  cv::Rect roi;                      // empty: the whole image
  double min_texture_std = 0.002;    // of full scale
  double max_masked_fraction = 0.5;  // of a window's pixels

  std::string Validate() const;  // empty when valid
};

EvaluationResult evaluate_flow(const cv::Mat& reference, const cv::Mat& measurement, const FlowOptions& options,
                               const cv::Mat& mask = {});

// The dense flow (CV_32FC2, u then v) of a pair, for maps and tests.
// A colour pair's conversion is warned of into `warnings` (nullptr: silently).
cv::Mat dense_flow(const cv::Mat& reference, const cv::Mat& measurement, FlowAlgorithm algorithm,
                   DisPreset dis_preset = DisPreset::kMedium, std::vector<std::string>* warnings = nullptr);

}  // namespace bosfuse::fusion
