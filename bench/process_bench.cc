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
//   build/bench/process_bench --benchmark_filter=-16MP --benchmark_repetitions=3
//   --benchmark_report_aggregates_only=true
//
// BM_ProcessRun16MP: the paper's 16 MP camera, 20 frames of 4928×3264 in
// 16-bit PNG with a plume whose deflection fades, full fields with the
// process defaults: each step in turn (/prefetch:0/aside:0), the next frame
// decoded ahead (/prefetch:1/aside:0), and also the last frame's
// temperature field and field files made aside (/prefetch:1/aside:1), each
// one frame at a time (/at_once:1); and two frames side by side
// (/at_once:2, the default on two cores: pipeline/frame_threads.h). The
// frames are PNGs as bosfuse's recorder writes them (/png:0: unfiltered and
// uncompressed, acquisition/cameras/frame_png.h), or, for comparison, as OpenCV
// writes a PNG by default (/png:1: compressed, filtered rows), as frames
// from other software may come; the pixels are the same.
// Counters: frames per second (wall); the peak resident memory of the
// processing (VmHWM, reset before each run; where the kernel cannot reset
// it, peak_is_lifetime = 1 and it is getrusage's maximum over the process's
// life: then run one variant per process); per frame, the costs besides the
// evaluation (ProcessReport::times). The frames are rendered once into a
// cache ($BOSFUSE_BENCH_CACHE, else $TMPDIR/bosfuse-bench-cache: 680 MB for
// /png:0, 660 MB more once /png:1 has run) and
// linked into a scratch run; rendering is never timed. Each run takes a
// minute or more: run it on its own, on a loaded machine one variant per
// process, alternating, e.g.
//   build/bench/process_bench --benchmark_filter='16MP/prefetch:1/aside:1'
// Figures: docs/BENCHMARKS.md, "Processing".
//
// BM_ProcessRun16MPRanks: the same run processed by the executable under
// `mpirun --oversubscribe -n RANKS bosfuse process --threads THREADS`
// (cluster/frame_farm.h); ranks:1 is one process started by mpirun, one
// frame at a time (--frames-at-once 1, which the ranks of a job are anyway).
// --bind-to none: Open MPI binds each of up to two ranks to one core by
// default, which would give a rank of two threads one core.
// Counters: frames per second (wall, MPI start-up included), the bytes of
// a frame's results sent to rank 0, and rank 0's time to write a frame's
// results into the run (its "writer's limit"), and the field files the
// ranks wrote per frame (on a cluster: to the shared filesystem). Figures and the scaling
// model: docs/BENCHMARKS.md, "Scaling out".
//   build/bench/process_bench --benchmark_filter=16MPRanks

#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "acquisition/cameras/frame_png.h"
#include "acquisition/cameras/image_file.h"
#include "fusion/bos_geometry.h"
#include "fusion/displacement_evaluator.h"
#include "fusion/temperature_field.h"
#include "pipeline/process.h"
#include "sim/synthetic_pair.h"
#include "storage/run_store.h"
#include "tests/support/subprocess.h"

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
        samples.push_back(
            {c, kStartNs + i * 1'000'000'000LL, std::nullopt, 20 + 30 * std::exp(-0.05 * t), std::nullopt, {}});
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

// ---- The 16 MP run ----

constexpr int kWidth16MP = 4928, kHeight16MP = 3264;
constexpr double kPlumeAxisXPx = 2464, kPlumeSourceYPx = 3000;

// Warm air rising from a source near the bottom: the background is pulled
// towards the column's axis (negative peak, as bump_gradient's hot spot), the
// column widening with height and fading in over its first 200 px.
cv::Point2d plume_shift_px(double x_px, double y_px, double peak_px) {
  const double height_px = kPlumeSourceYPx - y_px;
  if (height_px <= 0) return {0, 0};
  const double sigma_px = 120 + 0.15 * height_px;
  const double d = (x_px - kPlumeAxisXPx) / sigma_px;
  const double onset = 1 - std::exp(-height_px / 200);
  return {peak_px * onset * d * std::exp(0.5 - 0.5 * d * d), 0};  // d·e^(−d²/2) peaks at d = 1
}

double plume_peak_px(int frame) { return -1.5 * std::exp(-0.1 * frame); }

// How the run's frames are written: 0, as bosfuse's recorder writes them
// (acquisition/cameras/frame_png.h: unfiltered, uncompressed); 1, as OpenCV writes
// a PNG by default (zlib level 1, libpng's adaptive row filters), as frames
// from other software may come.
enum FramePng { kAsRecorded = 0, kOpenCvDefault = 1 };

fs::path frame_cache_dir(FramePng png) {
  const char* cache = std::getenv("BOSFUSE_BENCH_CACHE");
  // The name changes with anything that changes the frames.
  return (cache && *cache ? fs::path(cache) : fs::temp_directory_path() / "bosfuse-bench-cache") /
         (png == kAsRecorded ? "process16mp-v2-4928x3264-16bit-plume-recorded"
                             : "process16mp-v2-4928x3264-16bit-plume-opencv-default");
}

std::string frame_name(int frame) { return fmt::format("f{}.png", frame); }

void write_png(FramePng png, const fs::path& path, const cv::Mat& frame) {
  if (png == kAsRecorded) return acquisition::write_frame_png(path, frame);
  if (!cv::imwrite(path.string(), frame)) throw std::runtime_error("cannot write " + path.string());
}

// The reference (frame 0) and kFrames measurements as 16-bit PNG, written
// into the cache by `write(frame, path)` when it does not hold them yet (a
// partial writing is never taken for one: the folder gets its name when
// complete).
template <class WriteFrame>
fs::path cached_frames(const fs::path& dir, const WriteFrame& write) {
  if (fs::is_regular_file(dir / "complete")) return dir;
  const fs::path partial = dir.string() + ".partial-" + std::to_string(::getpid());
  fs::remove_all(partial);
  fs::create_directories(partial);
  for (int i = 0; i <= kFrames; ++i) write(i, partial / frame_name(i));
  std::ofstream(partial / "complete") << "done\n";
  std::error_code taken;
  fs::rename(partial, dir, taken);  // another process may have finished first: then its frames serve
  if (taken) fs::remove_all(partial);
  return dir;
}

// The frames rendered once (as recorded), and re-encoded from those for
// kOpenCvDefault: the same pixels either way.
fs::path cached_16mp_frames(FramePng png) {
  if (png == kOpenCvDefault) {
    const fs::path recorded = cached_16mp_frames(kAsRecorded);
    return cached_frames(frame_cache_dir(png), [&](int i, const fs::path& path) {
      write_png(png, path, acquisition::read_image_file(recorded / frame_name(i)));
    });
  }
  sim::PatternOptions options;
  options.width_px = kWidth16MP;
  options.height_px = kHeight16MP;
  const sim::BackgroundPattern pattern = sim::generate_pattern(options);
  return cached_frames(frame_cache_dir(png), [&](int i, const fs::path& path) {
    const double peak_px = plume_peak_px(i);
    cv::Mat dots =
        i == 0 ? sim::render_dots(pattern, nullptr)
               : sim::render_dots(pattern, [peak_px](double x, double y) { return plume_shift_px(x, y, peak_px); });
    write_png(png, path, sim::camera_image(std::move(dots), 0, 0.01, 16, static_cast<std::uint64_t>(i + 1), 1));
  });
}

// A fresh run over the cached frames (hard links, else copies), removed at exit.
const fs::path& sixteen_megapixel_run(FramePng png = kAsRecorded) {
  static std::map<FramePng, ScratchDir> runs;
  if (const auto made = runs.find(png); made != runs.end()) return made->second.path;
  const fs::path frames = cached_16mp_frames(png);
  const fs::path run =
      fs::temp_directory_path() / fmt::format("bosfuse-process-bench-16mp-{}-{}", static_cast<int>(png), ::getpid());
  fs::remove_all(run);
  auto store = storage::RunStore::create(run, {0, "bench 16 MP", kStartNs, std::nullopt, "", {}, 1.0, std::nullopt},
                                         storage::RunStore::CreateMode::kNew);
  const auto device = store.add_device({0, "daq", "modbus-tcp", "generic", "sim"});
  std::vector<std::int64_t> channels{
      store.add_channel({0, device, "tc1", "thermocouple", "degC", "K", kPlumeAxisXPx + 150, 2200.0}),
      store.add_channel({0, device, "tc2", "thermocouple", "degC", "K", kPlumeAxisXPx - 250, 1400.0})};
  std::vector<storage::Sample> samples;
  for (int i = 0; i <= 2 * kFrames; ++i) {
    for (auto c : channels) {
      samples.push_back(
          {c, kStartNs + i * 1'000'000'000LL, std::nullopt, 20 + 30 * std::exp(-0.05 * i), std::nullopt, {}});
    }
  }
  store.write_samples(samples);
  fs::create_directories(run / "frames");
  for (int i = 0; i <= kFrames; ++i) {
    const std::string path = "frames/" + frame_name(i);
    std::error_code not_linked;
    fs::create_hard_link(frames / frame_name(i), run / path, not_linked);
    if (not_linked) fs::copy_file(frames / frame_name(i), run / path);
    store.add_frame(
        {0, std::nullopt, kStartNs + 2LL * i * 1'000'000'000, std::nullopt, path, kWidth16MP, kHeight16MP, 16, i == 0});
  }
  store.finish(storage::RunStatus::kComplete, kStartNs + 2LL * kFrames * 1'000'000'000);
  return runs[png].path = run;
}

// One 16 MP 16-bit frame of the run written and read back as each kind of
// PNG (op 0: written to a file, op 1: read with acquisition::read_image_file,
// as process reads a frame); file_MB, its size.
void BM_FramePng16MP(benchmark::State& state) {
  const auto png = static_cast<FramePng>(state.range(0));
  const bool reading = state.range(1) == 1;
  const fs::path source = cached_16mp_frames(png) / frame_name(5);
  const cv::Mat frame = acquisition::read_image_file(source);
  const ScratchDir dir{fs::temp_directory_path() / ("bosfuse-frame-png-bench-" + std::to_string(::getpid()))};
  fs::create_directories(dir.path);
  const fs::path written = dir.path / "frame.png";
  for (auto _ : state) {
    if (reading) {
      benchmark::DoNotOptimize(acquisition::read_image_file(source));
    } else {
      write_png(png, written, frame);
    }
  }
  state.counters["file_MB"] = static_cast<double>(fs::file_size(source)) / 1e6;
}
BENCHMARK(BM_FramePng16MP)
    ->ArgNames({"png", "op"})
    ->ArgsProduct({{kAsRecorded, kOpenCvDefault}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The peak resident memory, VmHWM, in MB; -1 when /proc does not say.
double peak_resident_mb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  }
  return -1;
}

// Starts the peak anew from the current resident size (Linux ≥ 4.0); false
// when the kernel refuses, and the peak is then the process's lifetime one.
bool reset_peak_resident() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

void BM_ProcessRun16MP(benchmark::State& state) {
  const fs::path& run = sixteen_megapixel_run(static_cast<FramePng>(state.range(3)));
  pipeline::ProcessOptions options;
  options.overrides.probes_only = false;
  options.prefetch_frames = static_cast<int>(state.range(0));
  options.finish_aside = state.range(1) != 0;
  options.frames_at_once = static_cast<int>(state.range(2));
  pipeline::ProcessReport report;
  bool peak_reset = true;
  for (auto _ : state) {
    state.PauseTiming();
    peak_reset = reset_peak_resident() && peak_reset;
    state.ResumeTiming();
    report = pipeline::process_run(run, options);
  }
  const pipeline::ProcessTimes& times = report.times;
  state.counters["temperature_analyses"] = report.temperature_analyses;
  state.counters["temperature_factorisations"] = report.temperature_factorisations;
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["peak_rss_MB"] = peak_reset ? peak_resident_mb() : usage.ru_maxrss / 1024.0;
  state.counters["peak_is_lifetime"] = peak_reset ? 0 : 1;
  // Per frame, the last iteration's: decode runs beside the evaluation when read ahead.
  const double per_frame_ms = 1e3 / kFrames;
  state.counters["decode_ms"] = times.decode_s * per_frame_ms;
  state.counters["wait_frame_ms"] = times.wait_for_frames_s * per_frame_ms;
  state.counters["evaluate_ms"] = times.evaluation_s * per_frame_ms;
  state.counters["temperature_ms"] = times.temperature_field_s * per_frame_ms;
  state.counters["csv_ms"] = times.csv_s * per_frame_ms;
  state.counters["wait_finish_ms"] = times.wait_for_finishing_s * per_frame_ms;
  state.counters["stage_ms"] = times.staging_s * per_frame_ms;
  state.counters["finish_ms"] = times.finishing_s * 1e3;  // once per run
}
BENCHMARK(BM_ProcessRun16MP)
    ->ArgNames({"prefetch", "aside", "at_once", "png"})
    ->Args({0, 0, 1, kAsRecorded})
    ->Args({1, 0, 1, kAsRecorded})
    ->Args({1, 1, 1, kAsRecorded})
    ->Args({1, 0, 2, kAsRecorded})
    ->Args({1, 0, 2, kOpenCvDefault})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

// The number after `label` in `text` (the job's report), 0 when absent.
double number_after(const std::string& text, const std::string& label) {
  const auto at = text.find(label);
  return at == std::string::npos ? 0 : std::atof(text.c_str() + at + label.size());
}

void BM_ProcessRun16MPRanks(benchmark::State& state) {
  const fs::path& run = sixteen_megapixel_run();
  // What Open MPI asks of root; harmless otherwise.
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  const std::string command = fmt::format(
      "mpirun --oversubscribe --bind-to none -n {} {}/bosfuse process {} --mode full --threads {} --frames-at-once 1 "
      "-q",
      state.range(0), BOSFUSE_BINARY_DIR, run.string(), state.range(1));
  std::string report;
  for (auto _ : state) {
    const auto job = testing::run_command(command, 900);
    if (job.exit_code != 0) throw std::runtime_error(command + " failed:\n" + job.output);
    report = job.output;
  }
  state.counters["frames_per_s"] = benchmark::Counter(kFrames, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["kB_per_frame_to_rank0"] = number_after(report, "results sent to rank 0: ");
  state.counters["rank0_write_ms"] = number_after(report, "rank 0 wrote the results: ");
  // What the ranks wrote beside: the field files, on the shared filesystem in a cluster.
  std::uintmax_t field_bytes = 0;
  for (const auto& f : fs::recursive_directory_iterator(run / "fields")) {
    if (f.is_regular_file()) field_bytes += f.file_size();
  }
  state.counters["field_files_MB_per_frame"] = static_cast<double>(field_bytes) / kFrames / 1e6;
}
BENCHMARK(BM_ProcessRun16MPRanks)
    ->ArgNames({"ranks", "threads"})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Args({2, 1})
    ->Args({2, 2})
    ->Args({3, 1})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
