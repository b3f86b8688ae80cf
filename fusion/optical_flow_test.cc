#include "fusion/optical_flow.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "fusion/displacement_evaluator.h"
#include "sim/synthetic_pair.h"

namespace bosfuse::fusion {
namespace {

sim::SyntheticPair render(const sim::DisplacementModel& field) {
  sim::PairOptions options;
  options.pattern.width_px = options.pattern.height_px = 192;
  options.field = field;
  return sim::render_pair(options);
}

double rms_error(const DisplacementField& field, const sim::DisplacementModel& truth) {
  double sum = 0;
  int n = 0;
  for (const auto& v : field.vectors) {
    if (!v.valid()) continue;
    const auto t = truth.window_mean(v.x_px, v.y_px, 16);
    sum += std::pow(v.u_px - t.x, 2) + std::pow(v.v_px - t.y, 2);
    ++n;
  }
  return n ? std::sqrt(sum / n) : 1e9;
}

// One table names the algorithms and presets both ways, for the commands and the stored settings.
TEST(OpticalFlow, AlgorithmAndPresetNamesReadBackAsTheirValues) {
  EXPECT_EQ(flow_algorithm_names(), (std::vector<std::string>{"dis", "farneback", "tvl1"}));
  for (const auto& name : flow_algorithm_names()) EXPECT_EQ(to_string(parse_flow_algorithm(name).value()), name);
  EXPECT_EQ(dis_preset_names(), (std::vector<std::string>{"ultrafast", "fast", "medium"}));
  for (const auto& name : dis_preset_names()) EXPECT_EQ(to_string(parse_dis_preset(name).value()), name);
  EXPECT_FALSE(parse_flow_algorithm("DIS").has_value());
  EXPECT_FALSE(parse_dis_preset("slow").has_value());
}

TEST(OpticalFlow, EveryAlgorithmFollowsAUniformShift) {
  const auto pair = render(sim::DisplacementModel::uniform(0.6, -0.4));
  for (const auto algorithm : {FlowAlgorithm::kDis, FlowAlgorithm::kFarneback, FlowAlgorithm::kTvl1}) {
    if (!flow_algorithm_available(algorithm)) continue;
    FlowOptions options;
    options.algorithm = algorithm;
    const auto result = evaluate_flow(pair.reference, pair.measurement, options);
    EXPECT_EQ(result.summary.method, "flow-" + to_string(algorithm));
    EXPECT_GT(result.field.count_valid(), result.field.size() * 9 / 10);
    EXPECT_LT(rms_error(result.field, pair.truth), 0.15) << to_string(algorithm);
  }
}

// Each preset is its own DIS: the fields differ, every one follows the shift,
// and medium (the default, with the variational refinement) is the closest.
TEST(OpticalFlow, EveryDisPresetFollowsAUniformShiftAndMediumIsTheClosest) {
  const auto pair = render(sim::DisplacementModel::uniform(0.6, -0.4));
  std::map<DisPreset, double> rms;
  cv::Mat previous;
  for (const auto preset : {DisPreset::kUltrafast, DisPreset::kFast, DisPreset::kMedium}) {
    FlowOptions options;
    options.dis_preset = preset;
    const auto result = evaluate_flow(pair.reference, pair.measurement, options);
    EXPECT_GT(result.field.count_valid(), result.field.size() * 9 / 10) << to_string(preset);
    rms[preset] = rms_error(result.field, pair.truth);
    EXPECT_LT(rms[preset], 0.25) << to_string(preset);
    const cv::Mat flow = dense_flow(pair.reference, pair.measurement, FlowAlgorithm::kDis, preset);
    if (!previous.empty()) {
      EXPECT_GT(cv::norm(flow, previous, cv::NORM_INF), 1e-4) << to_string(preset);
    }
    previous = flow;
  }
  EXPECT_LT(rms[DisPreset::kMedium], rms[DisPreset::kUltrafast]);
  EXPECT_EQ(FlowOptions{}.dis_preset, DisPreset::kMedium);
}

TEST(OpticalFlow, ReportsOnTheCrossCorrelationGrid) {
  const auto pair = render(sim::DisplacementModel::sinusoid(1.0, 96));
  EvaluatorOptions options;
  options.set_grid(16, 8);
  const auto xcorr = evaluate_displacement(pair.reference, pair.measurement, options);
  options.method = Method::kOpticalFlow;
  const auto flow = evaluate_displacement(pair.reference, pair.measurement, options);
  ASSERT_EQ(xcorr.field.size(), flow.field.size());
  for (std::size_t i = 0; i < flow.field.size(); ++i) {
    EXPECT_EQ(xcorr.field.vectors[i].x_px, flow.field.vectors[i].x_px);
    EXPECT_EQ(xcorr.field.vectors[i].y_px, flow.field.vectors[i].y_px);
  }
  EXPECT_LT(rms_error(flow.field, pair.truth), 0.2);
  const auto probes = probe_displacement(pair.reference, pair.measurement, {{95.5, 95.5}}, options);
  ASSERT_EQ(probes.field.size(), 1u);
  EXPECT_TRUE(probes.field.vectors[0].valid());
}

TEST(OpticalFlow, FlatAndMaskedWindowsAreFlagged) {
  const cv::Mat flat(64, 64, CV_8U, cv::Scalar(200));
  const auto result = evaluate_flow(flat, flat, FlowOptions{});
  EXPECT_EQ(result.field.count(VectorFlag::kNoTexture), result.field.size());
  const auto pair = render(sim::DisplacementModel::uniform(0.5, 0));
  const cv::Mat mask(192, 192, CV_8U, cv::Scalar(255));
  const auto masked = evaluate_flow(pair.reference, pair.measurement, FlowOptions{}, mask);
  EXPECT_EQ(masked.field.count(VectorFlag::kMasked), masked.field.size());
}

TEST(OpticalFlow, MismatchedSizesAreNamed) {
  const cv::Mat a(64, 64, CV_8U, cv::Scalar(0)), b(64, 32, CV_8U, cv::Scalar(0));
  try {
    evaluate_flow(a, b, FlowOptions{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sizes differ"), std::string::npos);
  }
}

}  // namespace
}  // namespace bosfuse::fusion
