// Writes the seed runs of stored_run_fuzz with the real run store:
//   stored_run_seed DIR   ->  DIR/complete.sqlite, DIR/running.sqlite
// A Modbus device with two thermocouples (ok, open-circuit, timeout and
// out-of-range samples), a camera with one frame record whose file is
// absent, events; one run finished, one never closed. fuzz/README.md
// says how they are shrunk (512-byte pages, no WAL) for the corpus.

#include <cstdio>
#include <filesystem>

#include "storage/run_store.h"

using namespace bosfuse::storage;
namespace fs = std::filesystem;

namespace {

void write_run(const fs::path& dir, bool finish) {
  fs::remove_all(dir);
  const std::int64_t t0 = 1'795'000'000'000'000'000;
  RunInfo info;
  info.name = "seed";
  info.started_ns = t0;
  info.config_toml = "[run]\nname = \"seed\"\n";
  RunStore store = RunStore::create(dir, info, RunStore::CreateMode::kNew);
  const auto module = store.add_device({0, "module", "modbus-tcp", "adam-6018", "127.0.0.1:1502"});
  const auto camera = store.add_device({0, "camera", "camera", "video", "0"});
  const auto a = store.add_channel({0, module, "tc-35mm", "thermocouple", "degC", "K", 812.0, 388.0});
  const auto b = store.add_channel({0, module, "tc-60mm", "thermocouple", "degC", "K", std::nullopt, std::nullopt});
  std::vector<Sample> samples;
  for (int i = 0; i < 4; ++i) {
    const std::int64_t t = t0 + i * 500'000'000LL;
    samples.push_back({a, t, std::nullopt, 80.0 - i, 800.0 - 10 * i, SampleStatus::kOk});
    const SampleStatus other[] = {SampleStatus::kOk, SampleStatus::kOpenCircuit, SampleStatus::kTimeout,
                                  SampleStatus::kOutOfRange};
    samples.push_back({b, t + 1000, t / 1000, other[i] == SampleStatus::kOk ? std::optional(60.5) : std::nullopt,
                       65535.0, other[i]});
  }
  store.write_samples(samples);
  store.write_events(std::vector<Event>{{0, module, t0 + 10, "connect", "connected"},
                                        {0, std::nullopt, t0 + 20, "gap", "a gap"}});
  store.add_frame({0, camera, t0 + 700'000'000, t0 + 690'000'000, "frames/camera/000001.png", 16, 12, 8, true});
  if (finish) store.finish(RunStatus::kComplete, t0 + 2'000'000'000);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  const fs::path out = argv[1];
  fs::create_directories(out);
  for (bool finish : {true, false}) {
    const fs::path dir = out / (finish ? "complete-run" : "running-run");
    write_run(dir, finish);
    fs::copy_file(dir / RunStore::kDatabaseFileName, out / (finish ? "complete.sqlite" : "running.sqlite"),
                  fs::copy_options::overwrite_existing);
    fs::remove_all(dir);
  }
  return 0;
}
