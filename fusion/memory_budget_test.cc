#include "fusion/memory_budget.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "fusion/displacement_evaluator.h"
#include "pipeline/available_memory.h"

namespace bosfuse::fusion {
namespace {

#ifdef BOSFUSE_SANITIZED
// Shadow memory and quarantines make resident and address-space sizes say
// nothing about what the code allocates.
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

constexpr std::uint64_t kMB = 1'000'000;

// A textured pair (blurred noise, the measurement shifted by a fraction of a
// pixel): what it costs to evaluate does not depend on the scene.
std::pair<cv::Mat, cv::Mat> textured_pair(cv::Size size, int type = CV_8UC1) {
  cv::Mat noise(size, CV_32F);
  cv::randu(noise, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, {0, 0}, 1.0);
  cv::Mat shifted;
  const cv::Matx23d shift(1, 0, 0.4, 0, 1, -0.3);
  cv::warpAffine(noise, shifted, shift, size, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  cv::Mat reference, measurement;
  const double scale = CV_MAT_DEPTH(type) == CV_16U ? 65535.0 : 255.0;
  noise.convertTo(reference, CV_MAT_DEPTH(type), scale);
  shifted.convertTo(measurement, CV_MAT_DEPTH(type), scale);
  if (CV_MAT_CN(type) == 3) {
    cv::cvtColor(reference, reference, cv::COLOR_GRAY2BGR);
    cv::cvtColor(measurement, measurement, cv::COLOR_GRAY2BGR);
  }
  return {reference, measurement};
}

std::uint64_t status_bytes(const char* key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) == 0) return std::stoull(line.substr(std::string(key).size())) * 1024;
  }
  return 0;
}

// Growth of the resident set's high-water mark while `run` runs: what it
// allocated and touched at its peak. Resets the mark first (clear_refs 5,
// Linux ≥ 4.0); false when that is not possible.
template <typename Run>
bool measure_peak_growth(Run run, std::uint64_t& growth_bytes) {
  {
    std::ofstream reset("/proc/self/clear_refs");
    if (!(reset << "5" << std::flush)) return false;
  }
  const std::uint64_t before = status_bytes("VmRSS:");
  run();
  growth_bytes = status_bytes("VmHWM:") - before;
  return true;
}

// Runs in a fresh process (a death test re-executes the test binary), so
// the heap holds nothing earlier tests freed that would hide the growth.
// `warm_up` first loads code pages, starts the thread pool and fills
// OpenCV's first-use tables, none of which `run` should be charged for.
// Exits 0 when the estimate bounds the measured peak from above within
// `factor`, 1 when not, 2 when the peak cannot be measured.
template <typename WarmUp, typename Run>
[[noreturn]] void compare_in_child(const std::string& what, std::uint64_t estimate, double factor, WarmUp warm_up,
                                   Run run) {
  warm_up();
  std::uint64_t measured = 0;
  if (!measure_peak_growth(run, measured)) std::_Exit(2);
  const bool ok = measured <= estimate && estimate <= factor * measured;
  std::fprintf(stderr, "%s: estimate %.1f MB, measured peak growth %.1f MB (estimate/measured %.3f)\n", what.c_str(),
               estimate / 1e6, measured / 1e6, double(estimate) / measured);
  std::_Exit(ok ? 0 : 1);
}

class MemoryBudgetMeasured : public ::testing::Test {
 protected:
  void SetUp() override {
    if (kSanitized) GTEST_SKIP() << "peak memory of instrumented code says nothing of the estimate";
    GTEST_FLAG_SET(death_test_style, "threadsafe");
  }
};

// The estimate is an upper bound of what an evaluation really takes at its
// peak, and a close one (within 20 %): a looser one would refuse pairs the
// machine can evaluate.
[[noreturn]] void compare_xcorr_in_child(const std::string& what, cv::Size size, int type, bool masked,
                                         const XcorrOptions& options) {
  const auto small = textured_pair({160, 120}, type);
  const auto pair = textured_pair(size, type);
  cv::Mat mask, small_mask;
  if (masked) {
    mask = cv::Mat::zeros(size, CV_8UC1);
    cv::circle(mask, {size.width / 2, size.height / 2}, size.height / 8, 255, -1);
    small_mask = cv::Mat::zeros(small.first.size(), CV_8UC1);
  }
  compare_in_child(
      what, xcorr_bytes_needed(PairShape::of(pair.first, mask), options), 1.2,
      [&] { (void)evaluate_xcorr(small.first, small.second, options, small_mask); },
      [&] { (void)evaluate_xcorr(pair.first, pair.second, options, mask); });
}

[[noreturn]] void compare_flow_in_child(const FlowOptions& options) {
  const auto small = textured_pair({160, 120});
  const auto pair = textured_pair({1200, 900});
  compare_in_child(
      "flow " + to_string(options.algorithm) + " " + to_string(options.dis_preset),
      flow_bytes_needed(PairShape::of(pair.first), options), 1.2,
      [&] { (void)evaluate_flow(small.first, small.second, options); },
      [&] { (void)evaluate_flow(pair.first, pair.second, options); });
}

void expect_xcorr_estimate_bounds_peak(const std::string& what, cv::Size size, int type, bool masked,
                                       const XcorrOptions& options) {
  EXPECT_EXIT(compare_xcorr_in_child(what, size, type, masked, options), ::testing::ExitedWithCode(0), "");
}

void expect_flow_estimate_bounds_peak(const FlowOptions& options) {
  EXPECT_EXIT(compare_flow_in_child(options), ::testing::ExitedWithCode(0), "");
}

TEST_F(MemoryBudgetMeasured, CrossCorrelationEstimateBoundsThePeakWithin20Percent) {
  expect_xcorr_estimate_bounds_peak("xcorr", {2400, 1800}, CV_8UC1, false, {});
}

TEST_F(MemoryBudgetMeasured, MaskedColourSixteenBitEstimateBoundsThePeakWithin20Percent) {
  XcorrOptions options;
  options.first_window_px = 32;
  options.symmetric_deformation = true;
  expect_xcorr_estimate_bounds_peak("xcorr 32->16, symmetric, masked 16-bit colour", {2000, 1500}, CV_16UC3, true,
                                    options);
}

TEST_F(MemoryBudgetMeasured, DisMediumEstimateBoundsThePeakWithin20Percent) { expect_flow_estimate_bounds_peak({}); }

TEST_F(MemoryBudgetMeasured, DisUltrafastAndFarnebackEstimatesBoundThePeakWithin20Percent) {
  FlowOptions ultrafast;
  ultrafast.dis_preset = DisPreset::kUltrafast;
  expect_flow_estimate_bounds_peak(ultrafast);
  FlowOptions farneback;
  farneback.algorithm = FlowAlgorithm::kFarneback;
  expect_flow_estimate_bounds_peak(farneback);
}

TEST(MemoryBudget, EstimateFollowsTheSettings) {
  const PairShape pair{{4000, 3000}, CV_8UC1};
  const XcorrOptions defaults;
  const std::uint64_t base = xcorr_bytes_needed(pair, defaults);
  // Float copies, the B-spline's coefficients (the image grown by 16 px),
  // the passes' one warped region (the ROI grown by the 5 px search reach),
  // 186626 nodes of 211 B, and 8 MB.
  EXPECT_EQ(base, 96 * kMB + 4ull * 4032 * 3032 + 4ull * 4010 * 3010 + 186626ull * 211 + (8ull << 20));
  XcorrOptions adaptive = defaults;
  adaptive.adaptive_refinement = true;
  // 499 nodes a row (4000 px, IW 16, step 8); the smoothing's rows: σ = 2
  // nodes, so 6 on each side, 27 rows of 3 × (499 + 12) doubles per thread.
  const std::uint64_t smoothing_rows = std::uint64_t(cv::getNumThreads()) * 27 * 3 * (499 + 12) * 8;
  EXPECT_EQ(xcorr_bytes_needed(pair, adaptive), base + 186626ull * 4 + smoothing_rows)
      << "the masks and the smoothing's rows";
  XcorrOptions fine = defaults;
  fine.step_px = 4;
  EXPECT_GT(xcorr_bytes_needed(pair, fine), base + 80 * kMB) << "four times the nodes";
  XcorrOptions region = defaults;
  region.roi = {0, 0, 1000, 1000};
  EXPECT_LT(xcorr_bytes_needed(pair, region), base - 70 * kMB) << "the warp and the grid cover the ROI only";
  EXPECT_GT(xcorr_bytes_needed(pair, region), 96 * kMB) << "the float copies are of the whole image";
  const PairShape colour{{4000, 3000}, CV_16UC3, CV_8UC1};
  EXPECT_EQ(xcorr_bytes_needed(colour, defaults), base + 12 * kMB + 4001ull * 3001 * 4)
      << "the exclusion mask and its integral are held through the passes";
  // Flow: DIS medium is the hungriest by far.
  FlowOptions dis;
  FlowOptions ultrafast;
  ultrafast.dis_preset = DisPreset::kUltrafast;
  EXPECT_GT(flow_bytes_needed(pair, dis), 2600 * kMB);
  EXPECT_LT(flow_bytes_needed(pair, ultrafast), 800 * kMB);
}

TEST(MemoryBudget, ARefusalSaysWhatIsNeededWhatIsAvailableAndWhatWouldFit) {
  AvailableMemory available;
  available.mem_available_bytes = 20'300 * kMB;
  available.address_space_bytes = 2'100 * kMB;
  const MemoryRequest request{{20000, 20000},
                              6'400 * kMB,
                              "window 16 px, 3 passes",
                              {"evaluate a region (--roi)", "use probe mode", "a machine with more memory"}};
  try {
    check_memory(request, available);
    FAIL() << "not refused";
  } catch (const InsufficientMemory& e) {
    EXPECT_EQ(std::string(e.what()),
              "a 20000×20000 pair needs 6.4 GB to evaluate with these settings (window 16 px, 3 passes); 2.1 GB are "
              "available to this process (the least of MemAvailable 20.3 GB, ulimit -v 2.1 GB); evaluate a region "
              "(--roi), use probe mode, or a machine with more memory");
  }
  EXPECT_EQ(available.limited_by(), "ulimit -v");
  MemoryRequest fits = request;
  fits.needed_bytes = 2'000 * kMB;
  EXPECT_NO_THROW(check_memory(fits, available));
  EXPECT_NO_THROW(check_memory(request, AvailableMemory{})) << "nothing known: no refusal";
}

// Exits 0 when, under an address-space limit of half what the field needs,
// the field is refused with the limit named and two probes are measured.
[[noreturn]] void refuse_field_keep_probes_in_child() {
  pipeline::install_memory_probe();  // what the program does at its start
  const auto pair = textured_pair({4000, 3000});
  const XcorrOptions options;
  const std::uint64_t needed = xcorr_bytes_needed(PairShape::of(pair.first), options);
  rlimit limit{};
  limit.rlim_cur = limit.rlim_max = status_bytes("VmSize:") + needed / 2;
  if (setrlimit(RLIMIT_AS, &limit) != 0) std::_Exit(3);
  const auto available = pipeline::available_memory();
  if (!available.address_space_bytes || *available.address_space_bytes > needed / 2) std::_Exit(4);
  try {
    (void)evaluate_xcorr(pair.first, pair.second, options);
    std::_Exit(5);
  } catch (const InsufficientMemory& e) {
    std::fprintf(stderr, "%s\n", e.what());
    if (std::string(e.what()).find("ulimit -v") == std::string::npos) std::_Exit(6);
  }
  const std::vector<cv::Point2d> points{{1000, 1000}, {3000, 2000}};
  const auto probes = probe_xcorr(pair.first, pair.second, points, options);
  std::_Exit(probes.field.count_valid() == 2 ? 0 : 7);
}

// In a child whose address space is limited: the whole-field evaluation of
// a pair is refused before it allocates, probes of the same pair are not.
TEST(MemoryBudgetLimited, AnAddressSpaceLimitRefusesTheFieldButNotProbes) {
  if (kSanitized) GTEST_SKIP() << "sanitizers reserve terabytes of address space";
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(refuse_field_keep_probes_in_child(), ::testing::ExitedWithCode(0),
              "needs [0-9]+ MB to evaluate with these settings \\(window 16 px, step 8 px, 3 passes\\)");
}

TEST(MemoryBudget, BytesReadAsFreeAndDfPrintThem) {
  EXPECT_EQ(format_bytes(6'400'000'000), "6.4 GB");
  EXPECT_EQ(format_bytes(241'300'000), "241 MB");
  EXPECT_EQ(format_bytes(950), "950 bytes");
}

}  // namespace
}  // namespace bosfuse::fusion
