// Recording from a GenICam camera: Aravis' fake GigE Vision camera
// (arv-fake-gv-camera-0.8) on 127.0.0.1 streamed through GenicamSource and
// the FrameRecorder into a run, as `acquire` records it. Counters: frames
// recorded, frames lost (the recorder's failures), this process's CPU as %
// of one core (capture and storage; the fake camera is another process),
// and the camera-clock mapping's residual from the run's last `clock` event.
// docs/BENCHMARKS.md, "GenICam recording".

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <regex>
#include <thread>

#include "acquisition/cameras/frame_recorder.h"
#include "acquisition/cameras/genicam_cameras.h"
#include "acquisition/cameras/genicam_source.h"
#include "storage/run_store.h"
#include "storage/run_writer.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::acquisition {
namespace {

using namespace std::chrono_literals;

double genicam_bench_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

// args: side in pixels, frames/s asked for (0: the camera's most), seconds.
void BM_GenicamRecord(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  const double rate_hz = static_cast<double>(state.range(1));
  const auto duration = std::chrono::seconds(state.range(2));
  testing::BackgroundProcess fake(
      {"setpriv", "--pdeathsig", "KILL", "arv-fake-gv-camera-0.8", "-i", "127.0.0.1", "-s", "BENCH01"});
  for (int i = 0; i < 50 && !list_genicam_cameras({"127.0.0.1"}, false).front().problem.empty(); ++i) {
    std::this_thread::sleep_for(100ms);
  }
  for (auto _ : state) {
    testing::TempDir dir;
    auto store =
        storage::RunStore::create(dir / "run", {0, "bench", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                  storage::RunStore::CreateMode::kNew);
    const std::int64_t device = store.add_device({0, "mv", "camera", "genicam", "127.0.0.1"});
    storage::RunWriter writer(store, {200ms, 10'000});
    GenicamOptions o;
    o.device = "127.0.0.1";
    o.pixel_format = "Mono16";
    o.roi = GenicamRoi{0, 0, side, side};
    if (rate_hz > 0) o.frame_rate_hz = rate_hz;
    FrameRecorderOptions recorder_options;
    auto recorder = std::make_shared<FrameRecorder>(std::make_unique<GenicamSource>(o), "mv", device, store.dir(),
                                                    writer, recorder_options);
    const double cpu0 = genicam_bench_cpu_s();
    const auto wall0 = std::chrono::steady_clock::now();
    recorder->start();
    std::this_thread::sleep_for(duration);
    recorder->stop();
    writer.flush();
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    const auto stats = recorder->stats();
    state.counters["frames"] = static_cast<double>(stats.frames);
    state.counters["frames_per_s"] = static_cast<double>(stats.frames) / wall_s;
    state.counters["lost"] = static_cast<double>(stats.failures);
    state.counters["cpu_pct_of_core"] = 100 * (genicam_bench_cpu_s() - cpu0) / wall_s;
    const std::regex residual(R"(residual (\d+) µs RMS \((\d+) µs max\))");
    for (const storage::Event& e : store.events()) {
      std::smatch m;
      if (e.kind == "clock" && std::regex_search(e.message, m, residual)) {
        state.counters["residual_rms_us"] = std::stod(m[1]);
        state.counters["residual_max_us"] = std::stod(m[2]);
      }
    }
  }
}
BENCHMARK(BM_GenicamRecord)
    ->ArgNames({"side", "rate_hz", "seconds"})
    ->Args({1024, 20, 60})
    ->Args({2048, 0, 10})
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
}  // namespace bosfuse::acquisition

BENCHMARK_MAIN();
