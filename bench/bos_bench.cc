// BOS evaluation: run time against error on synthetic pairs with known
// displacement, and the paper's studies (step test, window size, dot size and
// coverage). Counters carry the errors; time is evaluation only (manual
// timing, rendering excluded).
//   build/bench/bos_bench --benchmark_counters_tabular=true
//   build/bench/bos_bench --benchmark_filter=FullFrame --benchmark_repetitions=3
//   build/bench/bos_bench --benchmark_filter=FullFrame16MPMethods --benchmark_repetitions=3
// Figures and what they mean: docs/BENCHMARKS.md, "BOS evaluation".

#include <benchmark/benchmark.h>

#include <cmath>
#include <opencv2/core/utility.hpp>
#include <stdexcept>
#include <vector>

#include "fusion/displacement_evaluator.h"
#include "sim/evaluation_study.h"

namespace bosfuse {
namespace {

// method: 0 xcorr, 1 flow DIS, 2 flow Farneback, 3 flow TV-L1.
fusion::EvaluatorOptions evaluator(int method, int window_px, int passes) {
  fusion::EvaluatorOptions e;
  if (method > 0) {
    e.method = fusion::Method::kOpticalFlow;
    e.flow.algorithm = method == 1   ? fusion::FlowAlgorithm::kDis
                       : method == 2 ? fusion::FlowAlgorithm::kFarneback
                                     : fusion::FlowAlgorithm::kTvl1;
  }
  e.set_grid(window_px, window_px / 2);
  e.xcorr.passes = passes;
  return e;
}

void report(benchmark::State& state, const sim::StudyResult& r) {
  state.SetIterationTime(r.seconds);
  state.counters["vectors_per_s"] = r.vectors_per_s;
  state.counters["bias_px"] = r.max_abs_bias_px;
  state.counters["rms_px"] = r.rms_px;
  state.counters["p95_px"] = r.p95_px;
  state.counters["valid_pct"] = r.vectors ? 100.0 * r.valid / r.vectors : 0;
}

// Method × IW × passes × noise (‰ of full scale), uniform shifts 0..1 px.
void BM_UniformShift(benchmark::State& state) {
  sim::StudyCase study;
  study.evaluator = evaluator(int(state.range(0)), int(state.range(1)), int(state.range(2)));
  study.noise_std = state.range(3) / 1000.0;
  for (auto _ : state) report(state, sim::run_uniform_study(study));
}
BENCHMARK(BM_UniformShift)
    ->ArgNames({"method", "iw", "passes", "noise_permille"})
    ->ArgsProduct({{0}, {32, 16, 8}, {1, 2, 3}, {0, 10, 30}})
    ->ArgsProduct({{1, 2, 3}, {16}, {1}, {10}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The paper's dot study: dot diameter (px) × coverage (%), IW 16, 3 passes.
void BM_DotSizeCoverage(benchmark::State& state) {
  sim::StudyCase study;
  study.evaluator = evaluator(0, 16, 3);
  study.dot_diameter_px = double(state.range(0));
  study.coverage = state.range(1) / 100.0;
  for (auto _ : state) report(state, sim::run_uniform_study(study));
}
BENCHMARK(BM_DotSizeCoverage)
    ->ArgNames({"dot_px", "coverage_pct"})
    ->ArgsProduct({{1, 2, 3, 4, 6}, {5, 10, 20, 35, 50}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The paper's step test: rise width (10%→90%) at IW 32, 16, 8, with 1 and 3
// passes; SNR as the paper takes it, 1/σ² of the plateau.
void BM_StepTest(benchmark::State& state) {
  auto e = evaluator(0, int(state.range(0)), int(state.range(1)));
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const auto step = sim::run_step_study(e);
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    state.counters["rise_width_px"] = step.rise_width_px;
    state.counters["plateau_err_px"] = step.plateau_error_px;
  }
}
BENCHMARK(BM_StepTest)
    ->ArgNames({"iw", "passes"})
    ->ArgsProduct({{32, 16, 8}, {1, 3}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// Error and SNR against IW on the paper's 1 px shift.
void BM_ErrorAgainstWindow(benchmark::State& state) {
  sim::StudyCase study;
  study.evaluator = evaluator(0, int(state.range(0)), int(state.range(1)));
  study.shifts_px = {1.0};
  study.size_px = 384;
  for (auto _ : state) {
    const auto r = sim::run_uniform_study(study);
    report(state, r);
    state.counters["snr"] = r.rms_px > 0 ? 1.0 / (r.rms_px * r.rms_px) : 0;
  }
}
BENCHMARK(BM_ErrorAgainstWindow)
    ->ArgNames({"iw", "passes"})
    ->ArgsProduct({{8, 16, 32, 64}, {1, 3}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// A 16-megapixel DSLR pair (4928×3264), rendered once.
const sim::SyntheticPair& full_frame() {
  static const sim::SyntheticPair pair = [] {
    sim::PairOptions options;
    options.pattern.width_px = 4928;
    options.pattern.height_px = 3264;
    options.field = sim::DisplacementModel::bump_gradient(2464, 1632, 600, 1.5);
    return sim::render_pair(options);
  }();
  return pair;
}

// IW 16, step 8, 3 passes with deformation; max shift 2 px (BOS).
void BM_FullFrame16MP(benchmark::State& state) {
  const auto& pair = full_frame();
  auto e = evaluator(0, 16, 3);
  e.set_grid(16, 8);
  e.xcorr.max_shift_px = 2;
  e.xcorr.convergence_px = 0;
  for (auto _ : state) {
    const auto result = fusion::evaluate_displacement(pair.reference, pair.measurement, e);
    state.counters["vectors"] = double(result.field.size());
    state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
  }
}
BENCHMARK(BM_FullFrame16MP)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(2);

// The true window-mean displacement at the nodes of the IW 16, step 8 grid
// of the 16 MP pair, computed once (250 305 nodes × 256 samples).
const std::vector<cv::Point2d>& full_frame_truth(const fusion::DisplacementField& field) {
  static const std::vector<cv::Point2d> truth = [&] {
    std::vector<cv::Point2d> t(field.vectors.size());
    cv::parallel_for_(cv::Range(0, int(t.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i) {
        t[i] = full_frame().truth.window_mean(field.vectors[i].x_px, field.vectors[i].y_px, 16);
      }
    });
    return t;
  }();
  if (truth.size() != field.vectors.size()) throw std::logic_error("the 16 MP truth is for another grid");
  return truth;
}

// RMS of |measured − true window mean| over the valid vectors, in double.
double full_frame_rms_px(const fusion::DisplacementField& field) {
  const auto& truth = full_frame_truth(field);
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < field.vectors.size(); ++i) {
    const auto& v = field.vectors[i];
    if (!v.valid()) continue;
    sum += std::pow(v.u_px - truth[i].x, 2) + std::pow(v.v_px - truth[i].y, 2);
    ++n;
  }
  return n ? std::sqrt(sum / double(n)) : std::nan("");
}

// The 16 MP pair by method, in one run so time and error compare side by
// side (all on the IW 16, step 8 grid; max shift 2 px):
//   0  cross-correlation, 3 passes at IW 16 (BM_FullFrame16MP);
//   1  cross-correlation 32→16: a first pass at IW 32, then IW 16 (2 passes);
//   2  cross-correlation 32→16→16 (3 passes);
//   3  DIS optical flow, medium preset (the default), averaged per window;
//   4  DIS ultrafast.
// rms_px: against the true window-mean displacement, over valid vectors.
// DIS medium needs 3.7 GB and takes about 5× cross-correlation's time.
void BM_FullFrame16MPMethods(benchmark::State& state) {
  const auto& pair = full_frame();
  const int method = int(state.range(0));
  auto e = evaluator(method >= 3 ? 1 : 0, 16, method == 1 ? 2 : 3);
  e.set_grid(16, 8);
  e.xcorr.max_shift_px = 2;
  e.xcorr.convergence_px = 0;
  if (method == 1 || method == 2) e.xcorr.first_window_px = 32;
  e.flow.dis_preset = method == 4 ? fusion::DisPreset::kUltrafast : fusion::DisPreset::kMedium;
  fusion::EvaluationResult result;
  for (auto _ : state) result = fusion::evaluate_displacement(pair.reference, pair.measurement, e);
  const char* labels[] = {"xcorr 16,16,16", "xcorr 32,16", "xcorr 32,16,16", "flow-dis medium", "flow-dis ultrafast"};
  state.SetLabel(labels[method]);
  state.counters["rms_px"] = full_frame_rms_px(result.field);
  state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
}
BENCHMARK(BM_FullFrame16MPMethods)
    ->ArgName("method")
    ->DenseRange(0, 4)
    ->MeasureProcessCPUTime()  // all threads' CPU: steadier than wall time on a loaded machine
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// BM_FullFrame16MP frame after frame, as a run's processing does it: one
// evaluator for all iterations, so the reference's preparation and the
// buffers of the first frame serve the others (the first iteration, which
// prepares them, is outside the timing).
void BM_FullFrame16MPEvaluator(benchmark::State& state) {
  const auto& pair = full_frame();
  auto e = evaluator(0, 16, 3);
  e.set_grid(16, 8);
  e.xcorr.max_shift_px = 2;
  e.xcorr.convergence_px = 0;
  fusion::DisplacementEvaluator frames(pair.reference, e);
  frames.evaluate(pair.measurement);
  for (auto _ : state) {
    const auto result = frames.evaluate(pair.measurement);
    state.counters["vectors"] = double(result.field.size());
    state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
  }
}
BENCHMARK(BM_FullFrame16MPEvaluator)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(2);

// Probe mode: 10 thermocouple positions on the 16 MP pair, per pair.
void BM_Probe10(benchmark::State& state) {
  const auto& pair = full_frame();
  auto e = evaluator(0, 16, 3);
  e.xcorr.max_shift_px = 2;
  e.xcorr.probe_context_nodes = int(state.range(0));
  std::vector<cv::Point2d> points;
  for (int i = 0; i < 10; ++i) points.push_back({400.0 + 400 * i, 1000.0 + 100 * i});
  for (auto _ : state)
    benchmark::DoNotOptimize(fusion::probe_displacement(pair.reference, pair.measurement, points, e));
}
BENCHMARK(BM_Probe10)->ArgName("context_nodes")->Arg(1)->Arg(-1)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
