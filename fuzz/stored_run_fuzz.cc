// Stored-run reading (replay). The input bytes are written as run.sqlite in
// an empty folder, which is then read the way `bosfuse replay RUN` reads a
// recorded run: sim::inspect_recorded_run(), then for each device
// sim::replay_module_options() and the replay's experiment text from
// sim::replay_experiment_toml(), which must parse with parse_experiment();
// and through storage::RunStore::open() and each of its readers (run,
// devices, channels, read_samples, for_each_sample, events, frames,
// channel_summaries). Seeds are tiny runs written by the logger.
// Invariants: each step either succeeds or throws a std::exception with a
// message (a damaged file is an error, never a crash, hang or undefined
// behaviour); every sample read has a valid SampleStatus and a value only
// when kOk; read_samples is in time order; the replay's devices carry one
// sample list per channel, each in time order; the experiment file a replay
// generates from a run it accepted is one the logger accepts.

#include <cstdint>
#include <exception>

#include "acquisition/experiment_config.h"
#include "fuzz/fuzz_support.h"
#include "sim/replay.h"
#include "storage/run_store.h"

using namespace bosfuse;
using storage::SampleStatus;

namespace {

void check_sample(const storage::Sample& s) {
  const int status = static_cast<int>(s.status);
  FUZZ_CHECK(status >= 0 && status < storage::kSampleStatusCount);
  if (s.value) FUZZ_CHECK(s.status == SampleStatus::kOk);
}

void read_through_replay(const std::filesystem::path& dir) {
  sim::RecordedRun recorded;
  try {
    recorded = sim::inspect_recorded_run(dir);
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what()[0] != '\0');
    return;
  }
  std::vector<int> ports;
  for (const sim::ReplayDevice& device : recorded.devices) {
    FUZZ_CHECK(device.samples.size() == device.channels.size());
    for (const auto& samples : device.samples) {
      for (std::size_t i = 0; i < samples.size(); ++i) {
        check_sample(samples[i]);
        if (i > 0) FUZZ_CHECK(samples[i - 1].t_ns <= samples[i].t_ns);
      }
    }
    FUZZ_CHECK(device.period.count() > 0);
    (void)sim::replay_module_options(device, 0);  // does not start a server
    ports.push_back(15020 + static_cast<int>(ports.size()));
  }
  const std::string toml = sim::replay_experiment_toml(recorded, ports, 10.0);
  try {
    (void)acquisition::parse_experiment(toml, "replay.toml");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "replay experiment rejected: %s\n--- generated ---\n%s\n", e.what(), toml.c_str());
    FUZZ_CHECK(!"the replay of an accepted run generates an experiment file the logger accepts");
  }
}

void read_through_store(const std::filesystem::path& dir) {
  try {
    const storage::RunStore store = storage::RunStore::open(dir);
    (void)store.run();
    (void)store.devices();
    for (const auto& channel : store.channels()) {
      const auto samples = store.read_samples(channel.id);
      for (std::size_t i = 0; i < samples.size(); ++i) {
        check_sample(samples[i]);
        if (i > 0) FUZZ_CHECK(samples[i - 1].t_ns <= samples[i].t_ns);
      }
    }
    std::size_t visited = 0;
    store.for_each_sample([&](const storage::Sample& s) {
      check_sample(s);
      ++visited;
    });
    (void)store.events();
    (void)store.frames();
    (void)store.channel_summaries();
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what()[0] != '\0');
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::ScratchDir scratch;  // removed when the fuzzer exits
  const std::filesystem::path& dir = scratch.fresh();
  fuzz::write_file(dir / storage::RunStore::kDatabaseFileName, data, size);
  read_through_replay(dir);
  read_through_store(dir);
  return 0;
}
