// BOS evaluation: run time against error on synthetic pairs with known
// displacement, and the paper's studies (step test, window size, dot size and
// coverage). Counters carry the errors; time is evaluation only (manual
// timing, rendering excluded).
//   build/bench/bos_bench --benchmark_counters_tabular=true
//   build/bench/bos_bench --benchmark_filter=FullFrame --benchmark_repetitions=3
//   build/bench/bos_bench --benchmark_filter=FullFrame16MPMethods --benchmark_repetitions=3
// Figures and what they mean: docs/BENCHMARKS.md, "BOS evaluation".

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <opencv2/core/utility.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "fusion/displacement_evaluator.h"
#include "fusion/cross_correlation.h"
#include "pipeline/field_csv.h"
#include "pipeline/processing_settings.h"
#include "fusion/image_input.h"
#include "fusion/scene_match.h"
#include "fusion/search_range.h"
#include "fusion/adaptive_refinement.h"
#include "fusion/outlier_filter.h"
#include "fusion/simd_kernels.h"
#include "bench/bench_scenes.h"
#include "sim/evaluation_study.h"

namespace bosfuse {
namespace {

// method: 0 xcorr, 1 flow DIS, 2 flow Farneback, 3 flow TV-L1.
// The evaluator's options, the deformation's interpolator from
// BOSFUSE_BENCH_INTERPOLATOR when set (fusion::Interpolator's number: 1
// Lanczos-3, the former default, against the default for comparison), and
// adaptive refinement from BOSFUSE_BENCH_ADAPTIVE when set (0 full
// refinement, 1 adaptive: the accuracy tables either way).
fusion::XcorrOptions bench_xcorr() {
  fusion::XcorrOptions x;
  if (const char* i = std::getenv("BOSFUSE_BENCH_INTERPOLATOR")) x.interpolator = fusion::Interpolator(std::atoi(i));
  if (const char* a = std::getenv("BOSFUSE_BENCH_ADAPTIVE")) x.adaptive_refinement = std::atoi(a) != 0;
  return x;
}

fusion::EvaluatorOptions evaluator(int method, int window_px, int passes) {
  fusion::EvaluatorOptions e;
  e.xcorr = bench_xcorr();
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
  state.counters["wrong_pct"] = r.compared ? 100.0 * r.wrong / r.compared : 0;
  state.counters["beyond_3sigma_pct"] = r.compared ? 100.0 * r.beyond_3_sigma / r.compared : 0;
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

// The full-field benchmarks' evaluation: IW 16, step 8, with deformation,
// every pass run; max shift 2 px (BOS).
// first_window_px 32 with 2 passes: the 32→16 schedule.
fusion::EvaluatorOptions full_frame_options(int method = 0, int passes = 3, int first_window_px = 0) {
  auto e = evaluator(method, 16, passes);
  e.xcorr.first_window_px = first_window_px;
  e.set_grid(16, 8);
  e.xcorr.max_shift_px = 2;
  e.xcorr.convergence_px = 0;
  return e;
}

// 3 passes.
void BM_FullFrame16MP(benchmark::State& state) {
  const auto& pair = full_frame();
  const auto e = full_frame_options();
  for (auto _ : state) {
    const auto result = fusion::evaluate_displacement(pair.reference, pair.measurement, e);
    state.counters["vectors"] = double(result.field.size());
    state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
  }
}
BENCHMARK(BM_FullFrame16MP)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(2);

// The quintic B-spline's prefilter of one 16 MP measurement (once per frame,
// before the deformed passes): its share of BM_FullFrame16MPEvaluator.
void BM_BSplineCoefficients16MP(benchmark::State& state) {
  cv::Mat image(4096, 4096, CV_32F), coefficients;
  cv::randu(image, 0.0, 1.0);
  for (auto _ : state) fusion::bspline_coefficients(image, fusion::Interpolator::kBSpline5, coefficients);
}
BENCHMARK(BM_BSplineCoefficients16MP)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(5);

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
  auto e = full_frame_options(method >= 3 ? 1 : 0, method == 1 ? 2 : 3, method == 1 || method == 2 ? 32 : 0);
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
// prepares them, is outside the timing). schedule 0: 3 passes at IW 16;
// 1: 32→16 (BM_FullFrame16MPMethods' method 1).
void BM_FullFrame16MPEvaluator(benchmark::State& state) {
  const auto& pair = full_frame();
  const bool from_32 = state.range(0) == 1;
  auto options = full_frame_options(0, from_32 ? 2 : 3, from_32 ? 32 : 0);
  // sigma:0 leaves out the per-vector uncertainty: its cost is the difference.
  options.xcorr.estimate_uncertainty = state.range(1) == 1;
  fusion::DisplacementEvaluator frames(pair.reference, options);
  frames.evaluate(pair.measurement);
  for (auto _ : state) {
    const auto result = frames.evaluate(pair.measurement);
    state.counters["vectors"] = double(result.field.size());
    state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
  }
}
BENCHMARK(BM_FullFrame16MPEvaluator)
    ->ArgNames({"schedule", "sigma"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// A field on the 16 MP pair's grid (615×407 nodes, IW 16, step 8), every
// node measured; `node(x_px, y_px)` gives its vector.
template <typename Node>
fusion::DisplacementField field_16mp(Node node) {
  fusion::DisplacementField field;
  field.rows = 407;
  field.cols = 615;
  for (int r = 0; r < field.rows; ++r) {
    for (int c = 0; c < field.cols; ++c) field.vectors.push_back(node(7.5 + 8 * c, 7.5 + 8 * r));
  }
  return field;
}

// The displacement CSV of a 16 MP field (615×407 nodes) as `process`
// writes it per frame: /0 formats with fmt, as write_csv did before
// (kept here as the baseline), /1 is write_csv (std::to_chars). Written to
// /dev/null, so the figure is the formatting alone.
void BM_DisplacementCsv16MP(benchmark::State& state) {
  std::mt19937 random(3);
  std::normal_distribution<double> shift_px(0.0, 0.7);
  const auto field = field_16mp([&](double x_px, double y_px) {
    return fusion::DisplacementVector{
        x_px, y_px, shift_px(random), shift_px(random), 3 + std::abs(shift_px(random)), fusion::VectorFlag::kOk};
  });
  std::ofstream out("/dev/null");
  for (auto _ : state) {
    if (state.range(0) == 1) {
      pipeline::write_csv(field, out);
      continue;
    }
    fmt::memory_buffer text;
    const auto to = std::back_inserter(text);
    fmt::format_to(to, "{}\n", pipeline::field_csv_header(pipeline::kDisplacementColumns));
    for (const auto& v : field.vectors) {
      fmt::format_to(to, "{:.1f},{:.1f},{:.5f},{:.5f},{},{:.3f}\n", v.x_px, v.y_px, v.u_px, v.v_px, v.valid() ? 1 : 0,
                     v.peak_ratio);
    }
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
  }
}
BENCHMARK(BM_DisplacementCsv16MP)->ArgName("to_chars")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// ---- Search range found from the scene (fusion/search_range.h) ----

// The cost of the scene's sample on the 16 MP small-displacement pair (its
// bump peaks at 1.5 px, inside the default ±4 px): the sample alone, on the
// images as the evaluator converts them. Compare with BM_FullFrame16MP.
void BM_SearchRange16MP(benchmark::State& state) {
  const auto& pair = full_frame();
  const cv::Mat reference = fusion::to_grey_unit_float(pair.reference, "reference");
  const cv::Mat measurement = fusion::to_grey_unit_float(pair.measurement, "measurement");
  fusion::SearchRange range;
  for (auto _ : state) {
    range = fusion::find_search_range(reference, measurement, cv::Rect({0, 0}, reference.size()), {},
                                      fusion::SearchStart{}, fusion::SearchRangeOptions{});
  }
  state.counters["widened"] = range.widened;
  state.counters["max_shift_px"] = range.max_shift_px;
}
BENCHMARK(BM_SearchRange16MP)->UseRealTime()->Unit(benchmark::kMillisecond);

// Uniform shifts past the old default bound on the 768×768 pair,
// default options (the scene sets the search): case 0 (5.3, −3.7) px,
// |d| = 6.5; case 1 (14, 0) px. rms_px over the valid vectors; interior:
// more than one window from the border.
void BM_LargeShift(benchmark::State& state) {
  const bool fourteen = state.range(0) == 1;
  const double u = fourteen ? 14 : 5.3, v = fourteen ? 0 : -3.7;
  const auto pair = bench::large_shift_pair(u, v);
  fusion::EvaluationResult result;
  for (auto _ : state) result = fusion::evaluate_xcorr(pair.reference, pair.measurement, bench_xcorr());
  double sum = 0;
  std::size_t valid = 0, interior = 0, interior_valid = 0;
  for (const auto& vec : result.field.vectors) {
    const bool inside = vec.x_px > 24 && vec.y_px > 24 && vec.x_px < 768 - 24 && vec.y_px < 768 - 24;
    interior += inside;
    if (!vec.valid()) continue;
    sum += std::pow(vec.u_px - u, 2) + std::pow(vec.v_px - v, 2);
    ++valid;
    interior_valid += inside;
  }
  state.SetLabel(fourteen ? "(14, 0) px" : "(5.3, -3.7) px");
  state.counters["rms_px"] = valid ? std::sqrt(sum / double(valid)) : std::nan("");
  state.counters["interior_valid_pct"] = interior ? 100.0 * double(interior_valid) / double(interior) : 0;
  state.counters["max_shift_px"] = result.summary.max_shift_px;
  state.counters["first_window_px"] = result.summary.first_window_px;
}
BENCHMARK(BM_LargeShift)->ArgName("case")->Arg(0)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond)->Iterations(1);

// A CV_8U mask of the field's nodes marking the middle quarter of its rows:
// a band across it, as adaptive refinement selects around a plume.
cv::Mat middle_quarter(const fusion::DisplacementField& field) {
  cv::Mat band = cv::Mat::zeros(field.rows, field.cols, CV_8U);
  band.rowRange(field.rows * 3 / 8, field.rows * 5 / 8).setTo(1);
  return band;
}

// The outlier test of one pass on a 16 MP field (615×407 nodes of noisy
// shifts, a few per cent spurious), as each pass runs it.
void BM_OutlierTest16MP(benchmark::State& state) {
  std::mt19937 random(5);
  std::normal_distribution<double> shift_px(0.0, 0.05);
  std::uniform_real_distribution<double> spurious(0.0, 1.0);
  const auto field = field_16mp([&](double x_px, double y_px) {
    const double bump = spurious(random) < 0.02 ? 3.0 : 0.0;
    return fusion::DisplacementVector{
        x_px, y_px, 0.5 + shift_px(random) + bump, shift_px(random), 3, fusion::VectorFlag::kOk};
  });
  // /1: only a band across the middle quarter of the field, as adaptive
  // refinement tests around a plume.
  const cv::Mat band = middle_quarter(field);
  const cv::Mat* only = state.range(0) == 1 ? &band : nullptr;
  fusion::DisplacementField tested = field;
  for (auto _ : state) {
    state.PauseTiming();
    tested.vectors = field.vectors;
    state.ResumeTiming();
    state.counters["replaced"] = double(fusion::replace_outliers(tested, fusion::OutlierOptions{}, only));
  }
}
BENCHMARK(BM_OutlierTest16MP)
    ->ArgName("band")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// The first pass's two kernels per node, on one core, over the nodes of a
// 16 MP frame as the default first pass takes them (every other node of an
// 8 px grid, 16 px windows, ±5 px searches, along each row): /0 the search
// patch's box sums (patch_box_sums), /1 the window's products with it
// (accumulate_products). Random pixels; per_node (seconds) is the figure.
void BM_FirstPassKernels16MP(benchmark::State& state) {
  constexpr int kWidth = 4928, kHeight = 3264, kWindow = 16, kRadius = 5, kStep = 16;
  constexpr int kPatch = kWindow + 2 * kRadius, kSide = 2 * kRadius + 1;
  std::mt19937 random(13);
  std::uniform_real_distribution<float> grey(0.f, 1.f);
  std::vector<float> image(std::size_t(kWidth) * kHeight), reference(kWindow * kWindow);
  for (auto& v : image) v = grey(random);
  for (auto& v : reference) v = grey(random) - 0.5f;
  std::vector<double> scratch(2 * kSide * kPatch), sums(kSide * kSide), squares(kSide * kSide);
  const bool products = state.range(0) == 1;
  int nodes = 0;
  for (auto _ : state) {
    nodes = 0;
    for (int y = 0; y + kPatch <= kHeight; y += kStep) {
      for (int x = 0; x + kPatch <= kWidth; x += kStep, ++nodes) {
        const float* patch = image.data() + std::size_t(y) * kWidth + x;
        if (products) {
          fusion::accumulate_products(reference.data(), patch, kWidth, kWindow, kSide, sums.data());
        } else {
          fusion::patch_box_sums(patch, kWidth, kPatch, kWindow, scratch.data(), sums.data(), squares.data());
        }
        benchmark::DoNotOptimize(sums.data());
      }
    }
  }
  state.counters["per_node"] = benchmark::Counter(
      double(nodes), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_FirstPassKernels16MP)->ArgName("products")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Adaptive refinement's per-frame selection work on a 16 MP field (615×407
// nodes, noise 0.05 px): /0 the noise floor of a coarse first pass (every
// other node, 308×204), /1 smoothing the unrefined nodes with a quarter of
// the field refined (a band across it, as around a plume).
void BM_AdaptiveSelection16MP(benchmark::State& state) {
  std::mt19937 random(9);
  std::normal_distribution<double> shift_px(0.0, 0.05);
  auto noisy = [&](double x_px, double y_px) {
    return fusion::DisplacementVector{x_px, y_px, shift_px(random), shift_px(random), 3, fusion::VectorFlag::kOk};
  };
  const auto field = field_16mp(noisy);
  if (state.range(0) == 0) {
    fusion::DisplacementField coarse;
    coarse.rows = 204;
    coarse.cols = 308;
    for (int i = 0; i < coarse.rows * coarse.cols; ++i) coarse.vectors.push_back(noisy(0, 0));
    for (auto _ : state) benchmark::DoNotOptimize(fusion::field_noise_floor_px(coarse));
    return;
  }
  const cv::Mat refine = middle_quarter(field);
  fusion::SmoothingBuffers buffers;
  fusion::DisplacementField smoothed = field;
  for (auto _ : state) {
    state.PauseTiming();
    smoothed.vectors = field.vectors;
    state.ResumeTiming();
    fusion::smooth_unrefined(smoothed, refine, 2, buffers);
  }
}
BENCHMARK(BM_AdaptiveSelection16MP)->ArgName("stage")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

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

// Adaptive refinement (XcorrOptions::adaptive_refinement) against full
// refinement. Scenes: 0, a plume-sized displacement on the 16 MP frame —
// the gradient of a Gaussian bump of radius 320 px (a DisplacementModel
// rather than ConvectionScene, whose window means would have to be
// integrated numerically), shifted by more than 0.05 px within ~1000 px of
// its centre, a fifth of the frame; 1, BM_FullFrame16MP's bump (radius
// 600 px, displaced almost everywhere); 2, a uniform shift (0.3, −0.2) px on
// a quarter of the frame (2464×1632). Errors against the true window mean
// over valid vectors; "displaced" nodes are those whose true shift exceeds
// 0.05 px, the others "still". adaptive: 0 off, 1 on, 2 on with a threshold
// nothing reaches (the cost of the first pass and the bookkeeping alone), 3
// on without smoothing the unrefined nodes. frames: 0 one-shot
// (evaluate_displacement, the reference prepared in the timing), 1 a frame
// after the first of one evaluator, as a run's processing evaluates.
const sim::SyntheticPair& adaptive_scene(int scene) {
  auto render = [](int width_px, int height_px, const sim::DisplacementModel& field) {
    sim::PairOptions options;
    options.pattern.width_px = width_px;
    options.pattern.height_px = height_px;
    options.field = field;
    return sim::render_pair(options);
  };
  if (scene == 1) return full_frame();
  if (scene == 2) {
    static const sim::SyntheticPair uniform = render(2464, 1632, sim::DisplacementModel::uniform(0.3, -0.2));
    return uniform;
  }
  static const sim::SyntheticPair plume =
      render(4928, 3264, sim::DisplacementModel::bump_gradient(2464, 1632, 320, 1.5));
  return plume;
}

// The true window means at the nodes of `field` (computed once per scene).
const std::vector<cv::Point2d>& window_means(int scene, const fusion::DisplacementField& field) {
  static std::map<int, std::vector<cv::Point2d>> cache;
  auto& means = cache[scene];
  if (means.size() != field.size()) {
    const auto& truth = adaptive_scene(scene).truth;
    means.resize(field.size());
    cv::parallel_for_(cv::Range(0, int(field.size())), [&](const cv::Range& range) {
      for (int i = range.start; i < range.end; ++i)
        means[i] = truth.window_mean(field.vectors[i].x_px, field.vectors[i].y_px, 16);
    });
  }
  return means;
}

// CPU seconds of all threads: on a loaded machine a steadier measure of the work than the wall time.
double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

void BM_AdaptiveRefinement(benchmark::State& state) {
  const int scene = int(state.range(0));
  const auto& pair = adaptive_scene(scene);
  auto e = full_frame_options();
  e.xcorr.adaptive_refinement = state.range(1) != 0;
  if (state.range(1) == 2) e.xcorr.adaptive_threshold = 1e9;      // refines (almost) nothing: the fixed cost
  if (state.range(1) == 3) e.xcorr.adaptive_smoothing_nodes = 0;  // the unrefined first pass as it is
  // frames:0 one-shot; frames:N a run's frames after the first, N of them
  // in a row through one evaluator, the mean per frame (a single frame
  // after the first still pays for caches and predictors the first left
  // cold; a run of hundreds does not).
  const int timed_frames = std::max<int>(1, int(state.range(2)));
  std::optional<fusion::DisplacementEvaluator> frames;
  if (state.range(2) > 0) {
    frames.emplace(pair.reference, e);
    frames->evaluate(pair.measurement);
  }
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start_s = process_cpu_s();
    fusion::EvaluationResult result;
    for (int frame = 0; frame < timed_frames; ++frame) {
      result = frames ? frames->evaluate(pair.measurement)
                      : fusion::evaluate_displacement(pair.reference, pair.measurement, e);
    }
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() /
                           timed_frames);
    state.counters["cpu_all_threads_s"] = (process_cpu_s() - cpu_start_s) / timed_frames;
    const auto& means = window_means(scene, result.field);
    double sum_sq[2] = {0, 0};
    std::size_t count[2] = {0, 0};
    for (std::size_t i = 0; i < result.field.size(); ++i) {
      const auto& v = result.field.vectors[i];
      if (!v.valid()) continue;
      const bool displaced = std::hypot(means[i].x, means[i].y) > 0.05;
      sum_sq[displaced] += std::pow(v.u_px - means[i].x, 2) + std::pow(v.v_px - means[i].y, 2);
      ++count[displaced];
    }
    auto rms = [](double s, std::size_t n) { return n ? std::sqrt(s / double(n)) : 0.0; };
    state.counters["refined_pct"] = 100 * result.summary.refined_fraction;
    state.counters["displaced_pct"] = 100.0 * count[1] / std::max<std::size_t>(1, count[0] + count[1]);
    state.counters["rms_px"] = rms(sum_sq[0] + sum_sq[1], count[0] + count[1]);
    state.counters["rms_displaced_px"] = rms(sum_sq[1], count[1]);
    state.counters["rms_still_px"] = rms(sum_sq[0], count[0]);
    state.counters["valid_pct"] = 100.0 * result.summary.valid / result.field.size();
  }
}
BENCHMARK(BM_AdaptiveRefinement)
    ->ArgNames({"scene", "adaptive", "frames"})
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2, 3}, {0, 1, 20}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// One timed frame: wall time and the process's CPU time (all threads).
struct FrameCost {
  double wall_s, cpu_s;
};

double median_of(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

// Medians over `pairs` pairs of runs of `first` and `second`, which goes
// first alternating; the ratios are first / second, pair by pair.
struct PairedMedians {
  double first_wall_s, second_wall_s, first_cpu_s, second_cpu_s, wall_ratio, cpu_ratio;
};

template <class First, class Second>
PairedMedians paired_medians(int pairs, First&& first, Second&& second) {
  std::vector<double> first_wall, second_wall, first_cpu, second_cpu, wall_ratio, cpu_ratio;
  for (int i = 0; i < pairs; ++i) {
    FrameCost f{}, s{};
    if (i % 2 == 0) {
      f = first();
      s = second();
    } else {
      s = second();
      f = first();
    }
    first_wall.push_back(f.wall_s);
    second_wall.push_back(s.wall_s);
    first_cpu.push_back(f.cpu_s);
    second_cpu.push_back(s.cpu_s);
    wall_ratio.push_back(f.wall_s / s.wall_s);
    cpu_ratio.push_back(f.cpu_s / s.cpu_s);
  }
  return {median_of(first_wall), median_of(second_wall), median_of(first_cpu),
          median_of(second_cpu), median_of(wall_ratio),  median_of(cpu_ratio)};
}

// Adaptive refinement's speed-up on a scene, measured in pairs of frames:
// one evaluator with full refinement and one with adaptive refinement take
// a frame each in turn (which goes first alternates), after a first frame
// each. This machine's speed drifts by tens of percent within a minute, so
// two separate runs' means (BM_AdaptiveRefinement) see different machines;
// the two frames of a pair see nearly the same one. The reported time is
// adaptive refinement's median frame; counters: full refinement's median
// frame, and the medians of the pairs' ratios of wall time and of CPU time
// (all threads).
void BM_AdaptiveSpeedup(benchmark::State& state) {
  const auto& pair = adaptive_scene(int(state.range(0)));
  const int pairs = int(state.range(1));
  auto full_options = full_frame_options(), adaptive_options = full_frame_options();
  adaptive_options.xcorr.adaptive_refinement = true;
  fusion::DisplacementEvaluator full(pair.reference, full_options), adaptive(pair.reference, adaptive_options);
  auto frame = [&](fusion::DisplacementEvaluator& evaluator) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start_s = process_cpu_s();
    benchmark::DoNotOptimize(evaluator.evaluate(pair.measurement));
    return FrameCost{std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                     process_cpu_s() - cpu_start_s};
  };
  frame(full);
  frame(adaptive);
  for (auto _ : state) {
    const PairedMedians m = paired_medians(pairs, [&] { return frame(full); }, [&] { return frame(adaptive); });
    state.SetIterationTime(m.second_wall_s);
    state.counters["full_ms"] = 1e3 * m.first_wall_s;
    state.counters["speedup"] = m.wall_ratio;
    state.counters["speedup_cpu"] = m.cpu_ratio;
  }
}
BENCHMARK(BM_AdaptiveSpeedup)
    ->ArgNames({"scene", "pairs"})
    ->Args({0, 21})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// ---- Preprocessing (docs/BENCHMARKS.md, "Preprocessing") ----

// A 512×512 pair with each of three sub-pixel uniform shifts; RMS error of
// the valid vectors a window from the border against the shift.
// preprocess: 0 none, 1 normalize, 2 highpass, 3 minmax, 4 denoise; noise
// in ‰; schedule, bits: 0 the defaults (16, 16, 16); +1 OpenPIV's windows
// (64 → 32 → 16, --first-window 64); +2 symmetric deformation; +4 the
// predictor unsmoothed between passes (as OpenPIV's, which interpolates it);
// +8 a parabola, not a Gaussian, through the peak after deformation
// (fusion/subpixel.h: what OpenPIV's correlation on a pedestal does).
fusion::EvaluatorOptions low_contrast_options(const benchmark::State& state) {
  fusion::EvaluatorOptions options;
  options.preprocess.method = static_cast<fusion::Preprocessing>(state.range(0));
  const auto schedule = state.range(2);
  if (schedule & 1) options.xcorr.first_window_px = 64;
  if (schedule & 2) options.xcorr.symmetric_deformation = true;
  if (schedule & 4) options.xcorr.smooth_predictor = false;
  if (schedule & 8) options.xcorr.refinement_subpixel = fusion::SubpixelEstimator::kParabola3Point;
  return options;
}

void BM_LowContrastTenBit(benchmark::State& state) {
  const double noise = state.range(1) * 1e-3;
  constexpr int kSize = bench::kLowContrastSize;
  const fusion::EvaluatorOptions options = low_contrast_options(state);
  double seconds = 0, sum_sq = 0;
  std::size_t compared = 0, vectors = 0, valid = 0;
  for (auto _ : state) {
    for (int i = 0; i < 3; ++i) {
      const auto pair = bench::low_contrast_pair(i, noise);
      const cv::Mat& reference = pair.reference;
      const cv::Mat& measurement = pair.measurement;
      const cv::Point2d shift = bench::low_contrast_shift(i);
      const auto start = std::chrono::steady_clock::now();
      const auto result = fusion::evaluate_displacement(reference, measurement, options);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (const auto& v : result.field.vectors) {
        ++vectors;
        if (!v.valid()) continue;
        ++valid;
        const int w = options.xcorr.window_px;
        if (v.x_px < w || v.y_px < w || v.x_px >= kSize - w || v.y_px >= kSize - w) continue;
        sum_sq += std::pow(v.u_px - shift.x, 2) + std::pow(v.v_px - shift.y, 2);
        ++compared;
      }
    }
    state.SetIterationTime(seconds);
  }
  const auto schedule = state.range(2);
  state.SetLabel(std::string(fusion::to_string(options.preprocess.method)) + (schedule & 1 ? " 64-32-16" : "") +
                 (schedule & 2 ? " symmetric" : "") + (schedule & 4 ? " unsmoothed" : "") +
                 (schedule & 8 ? " parabola" : ""));
  state.counters["rms_px"] = compared ? std::sqrt(sum_sq / compared) : 0;
  state.counters["valid_pct"] = vectors ? 100.0 * valid / vectors : 0;
}
BENCHMARK(BM_LowContrastTenBit)
    ->ArgNames({"preprocess", "noise_permille", "schedule"})
    ->ArgsProduct({{0, 1, 2, 3, 4}, {4, 10}, {0}})
    ->ArgsProduct({{0, 4}, {4, 10}, {1, 2, 3, 5, 8, 9}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The cost of each filter on one 16 MP frame (8-bit in, float out), what
// it adds to every frame of `process`.
void BM_Preprocess16MP(benchmark::State& state) {
  const auto& pair = full_frame();
  fusion::PreprocessOptions options;
  options.method = static_cast<fusion::Preprocessing>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(fusion::preprocess(pair.measurement, options).data);
  state.SetLabel(std::string(fusion::to_string(options.method)));
}
BENCHMARK(BM_Preprocess16MP)
    ->ArgName("preprocess")
    ->DenseRange(1, 4)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

// ---- Frames that do not match the reference (fusion/scene_match.h) ----

// What `process` adds to every frame to tell a foreign one: the matcher of
// the 16 MP reference (its moments kept, as FrameContext keeps it) on one
// measurement frame. match: 0 the frame of the same scene, 1 an unrelated
// background of the same size.
void BM_SceneMatch16MP(benchmark::State& state) {
  const auto& pair = full_frame();
  static const cv::Mat unrelated = [] {
    sim::PairOptions options;
    options.pattern.width_px = 4928;
    options.pattern.height_px = 3264;
    options.pattern.seed = 99;
    return sim::render_pair(options).reference;
  }();
  const fusion::SceneMatcher matcher(pair.reference);
  const cv::Mat& frame = state.range(0) ? unrelated : pair.measurement;
  fusion::SceneMatch match;
  for (auto _ : state) match = matcher.match(frame);
  state.counters["same_scene"] = match.same_scene();
  state.SetLabel(state.range(0) ? "unrelated background" : "same scene");
}
BENCHMARK(BM_SceneMatch16MP)->ArgName("unrelated")->Arg(0)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond);

// ---- Defaults against the alternatives (docs/BENCHMARKS.md, "Defaults") ----

// Each benchmark scene with `evaluate`'s default options (variant 0) and
// one change each: 1 adaptive refinement, 2 two passes, 3 four passes, 4 a
// 32 px first window (32→16), 5 --preprocess normalize, 6 --preprocess
// highpass. Scenes: 0 uniform shifts 0…1 px on 256² at 1 % noise (the
// accuracy table's study); 1 a sinusoid v = 1 px · sin(2πx/128) on 512²,
// 1 % noise; 2 the paper's step (rise width and plateau error); 3 the
// (5.3, −3.7) px shift on 768²; 4 the low-contrast 10-bit pairs at 0.4 %
// noise; 5 the 16 MP plume (adaptive_scene 0). Wall time one-shot, as
// `bosfuse evaluate` runs (reference prepared in the timing); RMS of the
// error magnitude over the valid vectors against the true window mean.
fusion::EvaluatorOptions defaults_variant(int variant) {
  auto e = pipeline::default_evaluator_with({});
  switch (variant) {
    case 1: e.xcorr.adaptive_refinement = true; break;
    case 2: e.xcorr.passes = 2; break;
    case 3: e.xcorr.passes = 4; break;
    case 4: e.xcorr.first_window_px = 32; break;
    case 5: e.preprocess.method = fusion::Preprocessing::kNormalize; break;
    case 6: e.preprocess.method = fusion::Preprocessing::kHighpass; break;
    default: break;
  }
  return e;
}

const char* const kVariantNames[] = {"default", "adaptive", "passes 2", "passes 4", "first window 32",
                                     "normalize", "highpass"};

// RMS against the truth's window mean over the valid vectors, and the valid share.
struct FieldError {
  double sum_sq = 0;
  std::size_t compared = 0, vectors = 0, valid = 0;
  void add(const fusion::DisplacementField& field, const sim::DisplacementModel& truth, int window_px,
           cv::Rect interior) {
    for (const auto& v : field.vectors) {
      ++vectors;
      if (!v.valid()) continue;
      ++valid;
      if (!interior.contains(cv::Point(int(v.x_px), int(v.y_px)))) continue;
      const cv::Point2d t = truth.window_mean(v.x_px, v.y_px, window_px);
      sum_sq += std::pow(v.u_px - t.x, 2) + std::pow(v.v_px - t.y, 2);
      ++compared;
    }
  }
  double rms() const { return compared ? std::sqrt(sum_sq / double(compared)) : std::nan(""); }
};

template <typename F>
double timed_s(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

const sim::SyntheticPair& sinusoid_scene() {
  static const sim::SyntheticPair pair = [] {
    sim::PairOptions options;
    options.pattern.width_px = options.pattern.height_px = 512;
    options.field = sim::DisplacementModel::sinusoid(1.0, 128);
    return sim::render_pair(options);
  }();
  return pair;
}

// One scene's evaluation under `e`: seconds, and the errors into `error`;
// `cpu_s` the evaluations' CPU (all threads), where the scene's pairs are
// evaluated here (the uniform and step studies render inside their timing: 0).
double evaluate_scene(int scene, const fusion::EvaluatorOptions& e, FieldError& error, double& cpu_s,
                      benchmark::State& state) {
  const int w = e.xcorr.window_px;
  cpu_s = 0;
  auto one = [&](const sim::SyntheticPair& pair) {
    fusion::EvaluationResult result;
    const double cpu_start_s = process_cpu_s();
    const double s = timed_s([&] { result = fusion::evaluate_displacement(pair.reference, pair.measurement, e); });
    cpu_s += process_cpu_s() - cpu_start_s;
    const cv::Size size = pair.reference.size();
    error.add(result.field, pair.truth, w, cv::Rect(w, w, size.width - 2 * w, size.height - 2 * w));
    return s;
  };
  switch (scene) {
    case 1: return one(sinusoid_scene());
    case 3: {
      static const sim::SyntheticPair pair = bench::large_shift_pair(5.3, -3.7);
      return one(pair);
    }
    case 4: {
      double s = 0;
      for (int i = 0; i < 3; ++i) s += one(bench::low_contrast_pair(i, 0.004));
      return s;
    }
    case 5: {
      // One evaluation first, untimed: the first of the process page-faults the 16 MP images and buffers.
      static const bool warm = [] {
        const auto& pair = adaptive_scene(0);
        benchmark::DoNotOptimize(fusion::evaluate_displacement(pair.reference, pair.measurement, defaults_variant(0)));
        return true;
      }();
      benchmark::DoNotOptimize(warm);
      return one(adaptive_scene(0));
    }
    default: break;
  }
  if (scene == 2) {
    sim::StepResult step;
    const double s = timed_s([&] { step = sim::run_step_study(e); });
    state.counters["rise_width_px"] = step.rise_width_px;
    state.counters["plateau_err_px"] = step.plateau_error_px;
    return s;
  }
  sim::StudyCase study;
  study.evaluator = e;
  const auto r = sim::run_uniform_study(study);
  state.counters["bias_px"] = r.max_abs_bias_px;
  error.sum_sq = r.rms_px * r.rms_px * double(r.compared);
  error.compared = r.compared;
  error.vectors = r.vectors;
  error.valid = r.valid;
  return r.seconds;
}

void BM_Defaults(benchmark::State& state) {
  const int scene = int(state.range(0)), variant = int(state.range(1));
  const auto e = defaults_variant(variant);
  const char* const scenes[] = {"uniform 0-1 px", "sinusoid 1 px/128", "step 1 px", "shift 6.5 px",
                                "low contrast 10-bit", "plume 16 MP"};
  for (auto _ : state) {
    FieldError error;
    double cpu_s = 0;
    state.SetIterationTime(evaluate_scene(scene, e, error, cpu_s, state));
    if (cpu_s > 0) state.counters["cpu_all_threads_s"] = cpu_s;
    if (scene != 2) {
      state.counters["rms_px"] = error.rms();
      state.counters["valid_pct"] = error.vectors ? 100.0 * double(error.valid) / double(error.vectors) : 0;
    }
  }
  state.SetLabel(fmt::format("{}, {}", scenes[scene], kVariantNames[variant]));
}
BENCHMARK(BM_Defaults)
    ->ArgNames({"scene", "variant"})
    ->ArgsProduct({{0, 1, 2, 3, 4, 5}, {0, 1, 2, 3, 4, 5, 6}})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// One-shot `evaluate` on the 16 MP plume with the defaults and with
// adaptive refinement, in pairs (which goes first alternates; each a fresh
// evaluator, the reference prepared in the timing), as BM_AdaptiveSpeedup
// pairs frames after the first. Reported: adaptive's median one-shot;
// counters: the default's median, the medians of the pairs' wall and CPU
// (all threads) ratios default / adaptive.
void BM_DefaultsAdaptiveOneShot(benchmark::State& state) {
  const auto& pair = adaptive_scene(0);
  const int pairs = int(state.range(0));
  const auto full_options = defaults_variant(0), adaptive_options = defaults_variant(1);
  auto one_shot = [&](const fusion::EvaluatorOptions& e) {
    const double cpu_start_s = process_cpu_s();
    const double wall_s =
        timed_s([&] { benchmark::DoNotOptimize(fusion::evaluate_displacement(pair.reference, pair.measurement, e)); });
    return FrameCost{wall_s, process_cpu_s() - cpu_start_s};
  };
  one_shot(full_options);  // the pages of the images and the first buffers
  for (auto _ : state) {
    const PairedMedians m =
        paired_medians(pairs, [&] { return one_shot(full_options); }, [&] { return one_shot(adaptive_options); });
    state.SetIterationTime(m.second_wall_s);
    state.counters["default_ms"] = 1e3 * m.first_wall_s;
    state.counters["default_cpu_s"] = m.first_cpu_s;
    state.counters["adaptive_cpu_s"] = m.second_cpu_s;
    state.counters["speedup"] = m.wall_ratio;
    state.counters["speedup_cpu"] = m.cpu_ratio;
  }
}
BENCHMARK(BM_DefaultsAdaptiveOneShot)
    ->ArgName("pairs")
    ->Arg(7)
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
