#include "fusion/optical_flow.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>
#include <utility>

#include "fusion/image_input.h"
#include "fusion/memory_budget.h"
#if BOSFUSE_HAVE_OPTFLOW
#include <opencv2/optflow.hpp>
#endif

namespace bosfuse::fusion {
namespace {

constexpr std::pair<FlowAlgorithm, std::string_view> kFlowAlgorithmNames[] = {
    {FlowAlgorithm::kDis, "dis"}, {FlowAlgorithm::kFarneback, "farneback"}, {FlowAlgorithm::kTvl1, "tvl1"}};
constexpr std::pair<DisPreset, std::string_view> kDisPresetNames[] = {
    {DisPreset::kUltrafast, "ultrafast"}, {DisPreset::kFast, "fast"}, {DisPreset::kMedium, "medium"}};

template <typename Enum, std::size_t N>
using NameTable = std::pair<Enum, std::string_view>[N];

template <typename Enum, std::size_t N>
std::string name_in(const NameTable<Enum, N>& table, Enum value) {
  for (const auto& [known, name] : table) {
    if (known == value) return std::string(name);
  }
  return "unknown";
}

template <typename Enum, std::size_t N>
std::optional<Enum> value_named(const NameTable<Enum, N>& table, std::string_view name) {
  for (const auto& [value, known] : table) {
    if (known == name) return value;
  }
  return std::nullopt;
}

template <typename Enum, std::size_t N>
std::vector<std::string> names_of(const NameTable<Enum, N>& table) {
  std::vector<std::string> names;
  for (const auto& [value, name] : table) names.emplace_back(name);
  return names;
}

cv::Mat to_8bit(const cv::Mat& unit) {
  cv::Mat out;
  unit.convertTo(out, CV_8U, 255.0);
  return out;
}

// Sum of a CV_64F integral image over a rectangle.
double box_sum(const cv::Mat& integral, cv::Rect r) {
  return integral.at<double>(r.y + r.height, r.x + r.width) - integral.at<double>(r.y, r.x + r.width) -
         integral.at<double>(r.y + r.height, r.x) + integral.at<double>(r.y, r.x);
}

}  // namespace

std::string to_string(FlowAlgorithm algorithm) { return name_in(kFlowAlgorithmNames, algorithm); }
std::optional<FlowAlgorithm> parse_flow_algorithm(std::string_view name) {
  return value_named(kFlowAlgorithmNames, name);
}
std::vector<std::string> flow_algorithm_names() { return names_of(kFlowAlgorithmNames); }

std::string to_string(DisPreset preset) { return name_in(kDisPresetNames, preset); }
std::optional<DisPreset> parse_dis_preset(std::string_view name) { return value_named(kDisPresetNames, name); }
std::vector<std::string> dis_preset_names() { return names_of(kDisPresetNames); }

bool flow_algorithm_available(FlowAlgorithm algorithm) {
#if BOSFUSE_HAVE_OPTFLOW
  (void)algorithm;
  return true;
#else
  return algorithm != FlowAlgorithm::kTvl1;
#endif
}

std::string FlowOptions::Validate() const {
  if (window_px < 1 || window_px > 128) return fmt::format("window must be 1 to 128 px, not {}", window_px);
  if (step_px < 1) return fmt::format("step must be at least 1 px, not {}", step_px);
  if (!flow_algorithm_available(algorithm)) {
    return "optical flow " + to_string(algorithm) + " needs OpenCV's optflow module, which this build lacks";
  }
  if (!(max_masked_fraction >= 0 && max_masked_fraction <= 1)) return "max masked fraction must be 0 to 1";
  return {};
}

cv::Mat dense_flow(const cv::Mat& reference, const cv::Mat& measurement, FlowAlgorithm algorithm,
                   DisPreset dis_preset, std::vector<std::string>* warnings) {
  const cv::Mat ref8 = to_8bit(to_grey_unit_float(reference, "reference", warnings));
  const cv::Mat meas8 = to_8bit(to_grey_unit_float(measurement, "measurement", warnings));
  cv::Mat flow(ref8.size(), CV_32FC2, cv::Scalar(0, 0));
  switch (algorithm) {
    case FlowAlgorithm::kDis: {
      const int preset = dis_preset == DisPreset::kUltrafast ? cv::DISOpticalFlow::PRESET_ULTRAFAST
                         : dis_preset == DisPreset::kFast    ? cv::DISOpticalFlow::PRESET_FAST
                                                             : cv::DISOpticalFlow::PRESET_MEDIUM;
      auto dis = cv::DISOpticalFlow::create(preset);
      dis->setFinestScale(0);  // full resolution: BOS shifts are sub-pixel
      dis->calc(ref8, meas8, flow);
      break;
    }
    case FlowAlgorithm::kFarneback:
      cv::calcOpticalFlowFarneback(ref8, meas8, flow, 0.5, 3, 15, 5, 5, 1.1, 0);
      break;
    case FlowAlgorithm::kTvl1:
#if BOSFUSE_HAVE_OPTFLOW
      cv::optflow::DualTVL1OpticalFlow::create()->calc(ref8, meas8, flow);
      break;
#else
      throw std::invalid_argument("optical flow tvl1 needs OpenCV's optflow module, which this build lacks");
#endif
  }
  cv::patchNaNs(flow, 0.0);
  return flow;
}

EvaluationResult evaluate_flow(const cv::Mat& reference, const cv::Mat& measurement, const FlowOptions& options,
                               const cv::Mat& mask) {
  const auto start = std::chrono::steady_clock::now();
  if (const auto problem = options.Validate(); !problem.empty()) throw std::invalid_argument(problem);
  check_image_pair(reference, measurement, mask);
  const cv::Rect roi = effective_roi(options.roi, reference.size());
  check_window_fits(options.window_px, roi.size());
  EvaluationResult result;
  if (std::string account = check_flow_memory(reference, mask, options); !account.empty()) {
    result.summary.notes.push_back(std::move(account));
  }
  const cv::Mat ref_unit = to_grey_unit_float(reference, "reference", &result.summary.warnings);
  const cv::Mat flow =
      dense_flow(reference, measurement, options.algorithm, options.dis_preset, &result.summary.warnings);
  cv::Mat channels[2], sum_u, sum_v, sum_ref, sum_ref_sq, sum_mask;
  cv::split(flow, channels);
  cv::integral(channels[0], sum_u, CV_64F);
  cv::integral(channels[1], sum_v, CV_64F);
  cv::integral(ref_unit, sum_ref, sum_ref_sq, CV_64F, CV_64F);
  const cv::Mat excluded = to_exclusion_mask(mask);
  if (!excluded.empty()) {
    cv::Mat ones;
    excluded.convertTo(ones, CV_8U, 1.0 / 255.0);
    cv::integral(ones, sum_mask, CV_64F);
  }
  result.summary.method = "flow-" + to_string(options.algorithm);
  const GridGeometry grid = evaluation_grid(roi, options.window_px, options.step_px);
  result.field = field_on_grid(grid);
  const int n = options.window_px;
  for (auto& vec : result.field.vectors) {
    const cv::Rect window(static_cast<int>(std::lround(vec.x_px - (n - 1) / 2.0)),
                          static_cast<int>(std::lround(vec.y_px - (n - 1) / 2.0)), n, n);
    const double count = double(n) * n;
    if (!excluded.empty() && (excluded.at<std::uint8_t>(int(vec.y_px), int(vec.x_px)) ||
                              box_sum(sum_mask, window) > options.max_masked_fraction * count)) {
      vec.flag = VectorFlag::kMasked;
      continue;
    }
    const double mean = box_sum(sum_ref, window) / count;
    const double variance =
        std::max(0.0, (box_sum(sum_ref_sq, window) - count * mean * mean) / std::max(1.0, count - 1));
    if (std::sqrt(variance) < options.min_texture_std) {
      vec.flag = VectorFlag::kNoTexture;
      continue;
    }
    vec.u_px = box_sum(sum_u, window) / count;
    vec.v_px = box_sum(sum_v, window) / count;
    vec.peak_ratio = 0;  // flow has no correlation peak
  }
  result.summary.passes_run = 1;
  result.summary.window_px_per_pass = {n};
  count_flags(result.field, result.summary);
  result.summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace bosfuse::fusion
