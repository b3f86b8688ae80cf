// Processing a run: probe mode against full fields, on the work
// `bosfuse process` does per frame (image reading and the run store
// excluded). A synthetic run of 20 frames of 1024×768 with a hot spot
// whose amplitude decays, two thermocouple probes, the process defaults
// (window 32, step 16, 3 passes, every pass run).
//   full:   evaluate_displacement + recover_temperature_field per frame
//   probes: probe_displacement at the two thermocouple positions per frame,
//           with the exact context (--probe-context -1: equal to the full
//           field) or one node of context (the default)
//   build/bench/process_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// Figures: docs/BENCHMARKS.md, "Processing".

#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/temperature_field.h"
#include "sim/synthetic_pair.h"

namespace bosfuse {
namespace {

constexpr int kFrames = 20;

struct SyntheticRun {
  cv::Mat reference;
  std::vector<cv::Mat> frames;
  std::vector<cv::Point2d> probes{{592.0, 384.0}, {512.0, 304.0}};
};

const SyntheticRun& synthetic_run() {
  static const SyntheticRun run = [] {
    SyntheticRun r;
    for (int i = 0; i < kFrames; ++i) {
      sim::PairOptions pair;
      pair.pattern.width_px = 1024;
      pair.pattern.height_px = 768;
      pair.field = sim::DisplacementModel::bump_gradient(512, 384, 80, -0.6 * std::exp(-0.05 * 2 * i));
      pair.noise_seed = static_cast<std::uint64_t>(i + 1);
      auto images = sim::render_pair(pair);
      if (i == 0) r.reference = images.reference;
      r.frames.push_back(images.measurement);
    }
    return r;
  }();
  return run;
}

fusion::EvaluatorOptions process_defaults() {
  fusion::EvaluatorOptions e;
  e.set_grid(32, 16);
  e.xcorr.passes = 3;
  e.xcorr.probe_context_nodes = -1;
  e.xcorr.convergence_px = 0;
  return e;
}

void BM_ProcessProbes(benchmark::State& state) {
  const auto& run = synthetic_run();
  const auto options = process_defaults();
  for (auto _ : state) {
    for (const auto& frame : run.frames) {
      benchmark::DoNotOptimize(fusion::probe_displacement(run.reference, frame, run.probes, options));
    }
  }
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ProcessProbes)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// `bosfuse process --mode probes` by default: one node of context around each
// probe (--probe-context 1); within ~0.01-0.02 px of the full field rather than
// equal to it.
void BM_ProcessProbesOneNodeContext(benchmark::State& state) {
  const auto& run = synthetic_run();
  auto options = process_defaults();
  options.xcorr.probe_context_nodes = 1;
  for (auto _ : state) {
    for (const auto& frame : run.frames) {
      benchmark::DoNotOptimize(fusion::probe_displacement(run.reference, frame, run.probes, options));
    }
  }
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ProcessProbesOneNodeContext)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ProcessFullFields(benchmark::State& state) {
  const auto& run = synthetic_run();
  const auto options = process_defaults();
  const fusion::BosGeometry geometry(fusion::BosGeometryOptions{});
  for (auto _ : state) {
    for (const auto& frame : run.frames) {
      const auto evaluated = fusion::evaluate_displacement(run.reference, frame, options);
      benchmark::DoNotOptimize(fusion::recover_temperature_field(evaluated.field, geometry));
    }
  }
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ProcessFullFields)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The Poisson integration alone, on the 63×47 grid of one full frame.
void BM_TemperatureFieldOnly(benchmark::State& state) {
  const auto& run = synthetic_run();
  const auto evaluated = fusion::evaluate_displacement(run.reference, run.frames[0], process_defaults());
  const fusion::BosGeometry geometry(fusion::BosGeometryOptions{});
  for (auto _ : state) benchmark::DoNotOptimize(fusion::recover_temperature_field(evaluated.field, geometry));
}
BENCHMARK(BM_TemperatureFieldOnly)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
