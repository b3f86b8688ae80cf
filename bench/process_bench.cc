// Processing a run, end to end as `bosfuse process` does it: the pipeline
// called in-process (pipeline/process.h) on a run on disk — frames read
// from PNG, evaluated against the reference, probes, fields written as CSV,
// temperature fields, Newton fits and agreement, results staged and swapped
// into the run store. A synthetic run of 20 frames of 1024×768 with a hot
// spot whose amplitude decays, two thermocouples at image positions, the
// process defaults (window 16 px, step 8 px, 3 passes, every pass run).
//   full:   full fields (the default mode)
//   probes: probe mode with one node of context (the default) or the exact
//           context (--probe-context -1: equal to the full field)
//   build/bench/process_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// Figures: docs/BENCHMARKS.md, "Processing".

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <unistd.h>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/temperature_field.h"
#include "pipeline/process.h"
#include "sim/synthetic_pair.h"
#include "storage/run_store.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 20;
constexpr std::int64_t kStartNs = 1'800'000'000'000'000'000;

// A scratch folder removed when the benchmark ends.
struct ScratchDir {
  fs::path path;
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

// The run, written once per benchmark process into a scratch folder.
const fs::path& synthetic_run() {
  static const ScratchDir dir{[] {
    const fs::path run = fs::temp_directory_path() / ("bosfuse-process-bench-" + std::to_string(::getpid()));
    fs::remove_all(run);
    auto store = storage::RunStore::create(run, {0, "bench", kStartNs, std::nullopt, "", {}, 1.0, std::nullopt},
                                           storage::RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "daq", "modbus-tcp", "generic", "sim"});
    std::vector<std::int64_t> channels{
        store.add_channel({0, device, "tc1", "thermocouple", "degC", "K", 592.0, 384.0}),
        store.add_channel({0, device, "tc2", "thermocouple", "degC", "K", 512.0, 304.0})};
    std::vector<storage::Sample> samples;
    for (int i = 0; i <= 2 * kFrames; ++i) {
      for (auto c : channels) {
        const double t = i;
        samples.push_back({c, kStartNs + i * 1'000'000'000LL, std::nullopt, 20 + 30 * std::exp(-0.05 * t),
                           std::nullopt, {}});
      }
    }
    store.write_samples(samples);
    fs::create_directories(run / "frames");
    for (int i = 0; i <= kFrames; ++i) {
      sim::PairOptions pair;
      pair.pattern.width_px = 1024;
      pair.pattern.height_px = 768;
      pair.field = sim::DisplacementModel::bump_gradient(512, 384, 80, -0.6 * std::exp(-0.05 * 2 * i));
      pair.noise_seed = static_cast<std::uint64_t>(i + 1);
      const auto images = sim::render_pair(pair);
      const std::string path = "frames/f" + std::to_string(i) + ".png";
      cv::imwrite((run / path).string(), i == 0 ? images.reference : images.measurement);
      store.add_frame({0, std::nullopt, kStartNs + 2LL * i * 1'000'000'000, std::nullopt, path, 1024, 768, 8, i == 0});
    }
    store.finish(storage::RunStatus::kComplete, kStartNs + 2LL * kFrames * 1'000'000'000);
    return run;
  }()};
  return dir.path;
}

void process(benchmark::State& state, const pipeline::SettingsOverrides& overrides) {
  const fs::path& run = synthetic_run();
  pipeline::ProcessOptions options;
  options.overrides = overrides;
  for (auto _ : state) benchmark::DoNotOptimize(pipeline::process_run(run, options));
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ProcessRunFullFields(benchmark::State& state) {
  pipeline::SettingsOverrides o;
  o.probes_only = false;
  process(state, o);
}
BENCHMARK(BM_ProcessRunFullFields)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// `bosfuse process --mode probes`: one node of context around each probe;
// within ~0.01-0.02 px of the full field rather than equal to it.
void BM_ProcessRunProbes(benchmark::State& state) {
  pipeline::SettingsOverrides o;
  o.probes_only = true;
  o.probe_context_nodes = 1;
  process(state, o);
}
BENCHMARK(BM_ProcessRunProbes)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ProcessRunProbesExact(benchmark::State& state) {
  pipeline::SettingsOverrides o;
  o.probes_only = true;
  o.probe_context_nodes = -1;
  process(state, o);
}
BENCHMARK(BM_ProcessRunProbesExact)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The Poisson integration alone, on the 127×95 grid of one full frame.
void BM_TemperatureFieldOnly(benchmark::State& state) {
  sim::PairOptions pair;
  pair.pattern.width_px = 1024;
  pair.pattern.height_px = 768;
  pair.field = sim::DisplacementModel::bump_gradient(512, 384, 80, -0.6);
  const auto images = sim::render_pair(pair);
  fusion::EvaluatorOptions options;
  options.set_grid(16, 8);
  const auto evaluated = fusion::evaluate_displacement(images.reference, images.measurement, options);
  const fusion::BosGeometry geometry(fusion::BosGeometryOptions{});
  for (auto _ : state) benchmark::DoNotOptimize(fusion::recover_temperature_field(evaluated.field, geometry));
}
BENCHMARK(BM_TemperatureFieldOnly)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
