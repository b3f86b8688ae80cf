#include "fusion/memory_budget.h"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <opencv2/core/utility.hpp>
#include <utility>

#include "fusion/evaluation.h"

namespace bosfuse::fusion {
namespace {

using Bytes = std::uint64_t;

// What does not grow with the image: each thread's correlation planes and
// warp row buffers, OpenCV's and TBB's first-use structures (under 3 MB
// measured), and a TBB worker's stack, which an address-space limit counts
// in full (4 MB) the first time a process evaluates.
constexpr Bytes kFixedBytes = Bytes{8} << 20;

// A refinement pass's grid at its peak (replace_outliers after run_pass):
// the field, the copy of it before the pass that measures the change (kept
// between passes), the predictor's u and v and its smoothing's scratch
// component (kept between passes and frames), the outlier flags and, at
// worst for every node, an outlier's index and its replacement value, and
// the reference window's mean and energy kept per node for each window size,
// and the integer peak kept per node for the final pass's uncertainty.
// predictor_from's peak (the field, two predictors, a work copy when there
// are gaps, fill flags and updates: 153 B) is below it.
constexpr Bytes kXcorrBytesPerNode = 2 * sizeof(DisplacementVector) + 3 * sizeof(double) + 1 + sizeof(std::size_t) +
                                     sizeof(cv::Point2d) + 2 * 2 * sizeof(double) + 2 * sizeof(std::int8_t);

// Adaptive refinement's, kept between frames: four masks (the selection,
// the outlier test's, and the nodes a pass reads its predictor at, with
// their ring). Its smoothing keeps a few rows per thread
// (adaptive_smoothing_bytes).
constexpr Bytes kAdaptiveBytesPerNode = 4;

// OpenCV's own buffers per pixel, full resolution (finest scale 0 for DIS):
// pyramids, gradients, flow components at every scale and, for DIS fast and
// medium, the variational refinement's. Measured as VmHWM growth of a fresh
// process on OpenCV 4.6 (45.4, 209.7, 212.8, 69.9 and 127.5 B/px at 1 and
// 3 MP alike), rounded up.
Bytes flow_library_bytes_per_pixel(const FlowOptions& options) {
  switch (options.algorithm) {
    case FlowAlgorithm::kDis:
      return options.dis_preset == DisPreset::kUltrafast ? 48 : 216;
    case FlowAlgorithm::kFarneback:
      return 72;
    case FlowAlgorithm::kTvl1:
      return 132;
  }
  return 216;
}

Bytes pixels(cv::Size size) { return Bytes(std::max(size.width, 0)) * Bytes(std::max(size.height, 0)); }

// to_grey_unit_float's grey copy of a colour image, alive while the float
// copy is made (one image at a time).
Bytes grey_copy_bytes(cv::Size size, int type) { return CV_MAT_CN(type) > 1 ? pixels(size) * CV_ELEM_SIZE1(type) : 0; }

Bytes nodes(cv::Rect roi, int window_px, int step_px) {
  const GridGeometry grid = evaluation_grid(roi, window_px, step_px);
  return Bytes(std::max(grid.rows, 0)) * Bytes(std::max(grid.cols, 0));
}

// smooth_unrefined's band of rows per thread (adaptive_refinement.cc): a
// padded row, the ring of 2·half + 1 rows, the row filtered across and up to
// 2·half rows waiting for the neighbouring band, three doubles a node.
Bytes adaptive_smoothing_bytes(cv::Rect roi, const XcorrOptions& options) {
  if (!options.adaptive_refinement || !(options.adaptive_smoothing_nodes > 0)) return 0;
  const GridGeometry grid = evaluation_grid(roi, options.window_px, options.step_px);
  const Bytes half = static_cast<Bytes>(std::ceil(3 * options.adaptive_smoothing_nodes));
  const Bytes values_per_row = 3 * (Bytes(std::max(grid.cols, 0)) + 2 * half);
  return Bytes(std::max(1, cv::getNumThreads())) * (4 * half + 3) * values_per_row * sizeof(double);
}

// The largest region a pass warps: the bounding box of its windows (inside
// the ROI) grown by the search reach.
Bytes warped_region_pixels(cv::Rect roi, const XcorrOptions& options) {
  int reach_px = std::max(options.search_radius_px(0), options.search_radius_px(1));
  if (!options.deform) reach_px += static_cast<int>(std::ceil(options.max_shift_px)) + 2;  // whole-pixel offsets
  return Bytes(roi.width + 2 * reach_px) * Bytes(roi.height + 2 * reach_px);
}

// Warped regions alive at once: the passes share one buffer (the coarse
// first pass too); symmetric deformation warps the reference into a second.
int warped_images_at_once(const XcorrOptions& options) {
  return options.passes > 1 && options.deform && options.symmetric_deformation ? 2 : 1;
}

std::string xcorr_settings(const XcorrOptions& options) {
  const auto windows = options.window_px_per_pass();
  const std::string window = windows.front() == windows.back()
                                 ? fmt::format("window {} px", windows.back())
                                 : fmt::format("window {}→{} px", windows.front(), windows.back());
  return fmt::format("{}, step {} px, {} passes", window, options.step_px, options.passes);
}

std::string flow_settings(const FlowOptions& options) {
  const std::string method = options.algorithm == FlowAlgorithm::kDis
                                 ? fmt::format("DIS optical flow, {} preset", to_string(options.dis_preset))
                                 : to_string(options.algorithm) + " optical flow";
  return fmt::format("{}, window {} px", method, options.window_px);
}

std::optional<Bytes> least(std::optional<Bytes> a, std::optional<Bytes> b) {
  if (!a) return b;
  if (!b) return a;
  return std::min(*a, *b);
}

std::atomic<AvailableMemoryProbe> installed_probe{nullptr};

std::optional<AvailableMemory> probe_available_memory() {
  const AvailableMemoryProbe probe = installed_probe.load();
  return probe ? probe() : std::nullopt;
}

std::string describe_sources(const AvailableMemory& m) {
  std::vector<std::string> parts;
  if (m.mem_available_bytes) parts.push_back("MemAvailable " + format_bytes(*m.mem_available_bytes));
  if (m.cgroup_bytes) parts.push_back("cgroup limit " + format_bytes(*m.cgroup_bytes));
  if (m.address_space_bytes) parts.push_back("ulimit -v " + format_bytes(*m.address_space_bytes));
  if (m.data_bytes) parts.push_back("ulimit -d " + format_bytes(*m.data_bytes));
  std::string text;
  for (const auto& p : parts) text += (text.empty() ? "" : ", ") + p;
  return text;
}

std::string join_remedies(const std::vector<std::string>& remedies) {
  std::string text;
  for (std::size_t i = 0; i < remedies.size(); ++i) {
    text += i == 0 ? "" : i + 1 == remedies.size() ? ", or " : ", ";
    text += remedies[i];
  }
  return text;
}

}  // namespace

PairShape PairShape::of(const cv::Mat& reference, const cv::Mat& mask) {
  return {reference.size(), reference.type(), mask.empty() ? -1 : mask.type()};
}

// As evaluate_xcorr allocates (cross_correlation.cc), the larger of two
// moments, plus the fixed part:
//   preparing: the float copies of reference and measurement (8 B/px), and
//     either a colour image's grey copy or, with a mask, the exclusion mask,
//     its 0/1 copy and CV_32S integral (6 B/px);
//   a pass: the float copies, the mask and its integral (5 B/px), the warped
//     regions (4 B/px of the ROI grown by the search reach, in one buffer
//     all passes reuse; two with symmetric deformation) and 211 B per grid
//     node (kXcorrBytesPerNode), 4 B more with adaptive refinement, and
//     its smoothing's rows per thread;
//   both: a B-spline deformation's coefficients of the measurement (4 B/px
//     of the image grown by kCoefficientBorderPx on every side; of the
//     reference too with symmetric deformation), alive from preparing to
//     the last pass.
std::uint64_t xcorr_bytes_needed(const PairShape& pair, const XcorrOptions& options) {
  const cv::Rect roi = effective_roi(options.roi, pair.size);
  const Bytes n = pixels(pair.size);
  const bool masked = pair.mask_type >= 0;
  const Bytes mask_integral = masked ? Bytes(pair.size.width + 1) * Bytes(pair.size.height + 1) * sizeof(int) : 0;
  const bool spline = options.passes > 1 && options.deform && needs_coefficients(options.interpolator);
  const Bytes coefficients = spline ? Bytes(options.symmetric_deformation ? 2 : 1) *
                                          Bytes(pair.size.width + 2 * kCoefficientBorderPx) *
                                          Bytes(pair.size.height + 2 * kCoefficientBorderPx) * sizeof(float)
                                    : 0;
  const Bytes float_copies = 2 * n * sizeof(float) + coefficients;
  const Bytes mask_bytes = masked ? n + mask_integral : 0;
  const Bytes preparing =
      float_copies + std::max(grey_copy_bytes(pair.size, pair.type),
                              masked ? mask_bytes + std::max(n, grey_copy_bytes(pair.size, pair.mask_type)) : 0);
  const Bytes pass = float_copies + mask_bytes +
                     Bytes(warped_images_at_once(options)) * warped_region_pixels(roi, options) * sizeof(float) +
                     nodes(roi, options.window_px, options.step_px) *
                         (kXcorrBytesPerNode + (options.adaptive_refinement ? kAdaptiveBytesPerNode : 0)) +
                     adaptive_smoothing_bytes(roi, options);
  return std::max(preparing, pass) + kFixedBytes;
}

// As evaluate_flow allocates (optical_flow.cc), the larger of two moments:
//   the flow: the reference's float copy (4 B/px), both images in 8 bits
//     (2), the flow (8) and the library's own buffers;
//   after it: the float copy, the flow, its two channels (8) and four CV_64F
//     integral images (32), with a mask its exclusion mask, 0/1 copy and
//     CV_64F integral (10);
// plus 48 B per grid node and the fixed part. Converting a colour image
// costs a grey copy, but only at a moment when far less is held.
std::uint64_t flow_bytes_needed(const PairShape& pair, const FlowOptions& options) {
  const Bytes n = pixels(pair.size);
  const Bytes during = n * (4 + 2 + 8 + flow_library_bytes_per_pixel(options));
  const Bytes after = n * (4 + 8 + 8 + 32 + (pair.mask_type >= 0 ? 10 : 0));
  const cv::Rect roi = effective_roi(options.roi, pair.size);
  return std::max(during, after) + nodes(roi, options.window_px, options.step_px) * sizeof(DisplacementVector) +
         kFixedBytes;
}

std::optional<std::uint64_t> AvailableMemory::bytes() const {
  return least(least(mem_available_bytes, cgroup_bytes), least(address_space_bytes, data_bytes));
}

std::string AvailableMemory::limited_by() const {
  const auto b = bytes();
  if (!b) return "nothing known";
  if (mem_available_bytes == b) return "MemAvailable";
  if (cgroup_bytes == b) return "the cgroup limit";
  if (address_space_bytes == b) return "ulimit -v";
  return "ulimit -d";
}

void install_available_memory_probe(AvailableMemoryProbe probe) { installed_probe.store(probe); }

std::string check_memory(const MemoryRequest& request, const AvailableMemory& available) {
  const auto bytes = available.bytes();
  std::string account = fmt::format("memory: {}x{} pair needs {} ({}); available {} ({})", request.size.width,
                                    request.size.height, format_bytes(request.needed_bytes), request.settings,
                                    bytes ? format_bytes(*bytes) : "unknown", describe_sources(available));
  if (!bytes || request.needed_bytes <= *bytes) return account;
  throw InsufficientMemory(fmt::format(
      "a {}×{} pair needs {} to evaluate with these settings ({}); {} are available to this process (the least of "
      "{}); {}",
      request.size.width, request.size.height, format_bytes(request.needed_bytes), request.settings,
      format_bytes(*bytes), describe_sources(available), join_remedies(request.remedies)));
}

std::string check_xcorr_memory(const cv::Mat& reference, const cv::Mat& mask, const XcorrOptions& options) {
  const std::optional<AvailableMemory> probed = probe_available_memory();
  if (!probed) return {};
  const AvailableMemory& available = *probed;
  const PairShape pair = PairShape::of(reference, mask);
  MemoryRequest request{pair.size, xcorr_bytes_needed(pair, options), xcorr_settings(options), {}};
  // A region only helps when the whole-image float copies fit on their own.
  XcorrOptions smallest_region = options;
  const int first = options.window_px_per_pass().front();
  smallest_region.roi = {0, 0, first, first};
  const auto bytes = available.bytes();
  if (bytes && xcorr_bytes_needed(pair, smallest_region) < *bytes)
    request.remedies.push_back("evaluate a region (--roi)");
  request.remedies.push_back("use probe mode (--probe)");
  request.remedies.push_back("a machine with more memory");
  return check_memory(request, available);
}

std::string check_flow_memory(const cv::Mat& reference, const cv::Mat& mask, const FlowOptions& options) {
  const std::optional<AvailableMemory> probed = probe_available_memory();
  if (!probed) return {};
  const AvailableMemory& available = *probed;
  const PairShape pair = PairShape::of(reference, mask);
  MemoryRequest request{pair.size, flow_bytes_needed(pair, options), flow_settings(options), {}};
  const auto fits = [&](Bytes needed) { return available.bytes() && needed < *available.bytes(); };
  if (options.algorithm == FlowAlgorithm::kDis && options.dis_preset != DisPreset::kUltrafast) {
    FlowOptions ultrafast = options;
    ultrafast.dis_preset = DisPreset::kUltrafast;
    const Bytes needed = flow_bytes_needed(pair, ultrafast);
    if (fits(needed))
      request.remedies.push_back("DIS's ultrafast preset (--dis-preset ultrafast, needs " + format_bytes(needed) + ")");
  }
  XcorrOptions xcorr;
  xcorr.window_px = std::clamp(options.window_px, 8, 128);
  xcorr.step_px = options.step_px;
  xcorr.roi = options.roi;
  if (const Bytes needed = xcorr_bytes_needed(pair, xcorr); fits(needed)) {
    request.remedies.push_back("cross-correlation (--method xcorr, needs " + format_bytes(needed) + ")");
  }
  request.remedies.push_back("a machine with more memory");
  return check_memory(request, available);
}

std::string format_bytes(std::uint64_t bytes) {
  if (bytes >= 1'000'000'000) return fmt::format("{:.1f} GB", bytes / 1e9);
  if (bytes >= 1'000'000) return fmt::format("{:.0f} MB", bytes / 1e6);
  if (bytes >= 1'000) return fmt::format("{:.0f} kB", bytes / 1e3);
  return fmt::format("{} bytes", bytes);
}

}  // namespace bosfuse::fusion
