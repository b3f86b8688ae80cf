// Throughput of the run store and of Modbus polling over loopback.
//   build/bench/run_store_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Figures and what they mean: docs/BENCHMARKS.md.

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <filesystem>
#include <random>
#include <thread>

#include "acquisition/drivers/modbus_device.h"
#include "sim/modbus_server.h"
#include "storage/run_store.h"
#include "storage/run_writer.h"

namespace bosfuse {
namespace {

namespace fs = std::filesystem;

struct ScratchRun {
  ScratchRun() : dir(fs::temp_directory_path() / ("bosfuse-bench-" + std::to_string(std::random_device{}()))) {
    store.emplace(storage::RunStore::create(dir, {0, "bench", 0, {}, "", storage::RunStatus::kRunning, 1.0, std::nullopt},
                                            storage::RunStore::CreateMode::kNew));
    const auto device = store->add_device({0, "bench", "modbus-tcp", "adam-6018", ""});
    for (int i = 0; i < 8; ++i) {
      channels.push_back(
          store->add_channel({0, device, "tc" + std::to_string(i), "thermocouple", "degC", "K", {}, {}}));
    }
  }
  ~ScratchRun() {
    store.reset();
    fs::remove_all(dir);
  }
  // 8 channels polled together, as a module delivers them.
  std::vector<storage::Sample> batch(std::int64_t first_poll, std::int64_t polls) const {
    std::vector<storage::Sample> samples;
    samples.reserve(static_cast<std::size_t>(polls) * channels.size());
    for (std::int64_t p = first_poll; p < first_poll + polls; ++p) {
      for (auto channel : channels) {
        samples.push_back({channel,
                           1'700'000'000'000'000'000 + p * 100'000'000,
                           {},
                           20.0 + 1e-3 * double(p % 1000),
                           double(p % 65535),
                           storage::SampleStatus::kOk});
      }
    }
    return samples;
  }

  fs::path dir;
  std::optional<storage::RunStore> store;
  std::vector<std::int64_t> channels;
};

// Samples per second committed with one transaction per batch.
void BM_WriteSamplesBatched(benchmark::State& state) {
  ScratchRun run;
  const std::int64_t polls = state.range(0) / 8;
  std::int64_t next = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const auto samples = run.batch(next, polls);
    next += polls;
    state.ResumeTiming();
    run.store->write_samples(samples);
  }
  state.SetItemsProcessed(state.iterations() * polls * 8);
}
BENCHMARK(BM_WriteSamplesBatched)->Arg(1'000)->Arg(10'000)->Arg(100'000)->UseRealTime()->Unit(benchmark::kMillisecond);

// Through the RunWriter, as the logger writes: each poll pushes its 8
// samples; the writer thread commits in the background. Time from the first
// push to the flush that commits the last sample.
void BM_RunWriterPollsOf8(benchmark::State& state) {
  ScratchRun run;
  storage::RunWriter writer(*run.store);
  const std::int64_t polls = state.range(0) / 8;
  std::int64_t next = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const auto samples = run.batch(next, polls);
    next += polls;
    state.ResumeTiming();
    for (std::size_t i = 0; i < samples.size(); i += 8) writer.push(std::span(samples).subspan(i, 8));
    writer.flush();
  }
  state.SetItemsProcessed(state.iterations() * polls * 8);
}
BENCHMARK(BM_RunWriterPollsOf8)->Arg(400'000)->UseRealTime()->Unit(benchmark::kMillisecond);

double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// What the commit interval costs a logger: 8 channels polled at 20 Hz for
// 3 s of real time, committed every `flush_ms` (the durability window).
// Counters: process CPU per second logged, and commits.
void BM_CommitInterval(benchmark::State& state) {
  constexpr int kPolls = 60;
  constexpr auto kPollPeriod = std::chrono::milliseconds(50);
  ScratchRun run;
  double cpu_s = 0;
  std::int64_t commits = 0;
  std::int64_t next = 0;
  for (auto _ : state) {
    storage::RunWriter writer(*run.store, {std::chrono::milliseconds(state.range(0)), 100'000});
    const double before = process_cpu_s();
    auto due = std::chrono::steady_clock::now();
    for (int poll = 0; poll < kPolls; ++poll) {
      writer.push(run.batch(next++, 1));
      due += kPollPeriod;
      std::this_thread::sleep_until(due);
    }
    writer.stop();
    cpu_s += process_cpu_s() - before;
    commits += writer.stats().batches_committed;
  }
  const double logged_s = static_cast<double>(state.iterations()) * kPolls * 0.05;
  state.counters["cpu_ms_per_s"] = 1e3 * cpu_s / logged_s;
  state.counters["commits_per_s"] = static_cast<double>(commits) / logged_s;
}
BENCHMARK(BM_CommitInterval)->Arg(50)->Arg(100)->Arg(250)->Iterations(1)->UseRealTime()->Unit(benchmark::kMillisecond);

// Polls per second of one 8-channel ADAM-6018 over loopback TCP.
void BM_ModbusTcpPoll(benchmark::State& state) {
  acquisition::ModbusEndpoint endpoint;
  endpoint.port = 0;
  sim::SimulatedModule module;
  module.inputs = 8;
  sim::ModbusSimServer server(sim::module_server_options(module, endpoint));
  server.start();
  endpoint.port = server.port();
  acquisition::ModbusDevice device("bench", "adam-6018", endpoint, sim::module_channels("adam-6018", 8, "K"),
                                   std::chrono::milliseconds(500));
  device.connect();
  for (auto _ : state) benchmark::DoNotOptimize(device.read());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ModbusTcpPoll)->UseRealTime()->MinTime(2.0);

}  // namespace
}  // namespace bosfuse

BENCHMARK_MAIN();
