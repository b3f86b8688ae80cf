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
// behaviour); every sample read has a valid SampleStatus. When SQLite's
// integrity_check finds the file sound, also: a sample has a value only when
// kOk (the schema's CHECK constraint); read_samples and each replay device's per-channel samples are in time
// order, and the experiment file a replay generates from a run it accepted
// is one the logger accepts (given unique, non-empty device names, channel
// names unique across devices and a time scale in range, as the logger
// writes them).

#include <sqlite3.h>

#include <cstdint>
#include <exception>
#include <set>
#include <string>

#include "acquisition/config/experiment_config.h"
#include "fuzz/fuzz_support.h"
#include "sim/replay.h"
#include "storage/run_store.h"

using namespace bosfuse;
using storage::SampleStatus;

namespace {

// SQLite's own verdict on the file. Time order and the uniqueness of names
// come from the file's indexes and constraints, so they are invariants only
// of a sound file; a damaged one must still never crash.
bool file_is_sound(const std::filesystem::path& file) {
  sqlite3* db = nullptr;
  bool ok = false;
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, "PRAGMA integrity_check(1)", -1, &stmt, nullptr) == SQLITE_OK &&
        sqlite3_step(stmt) == SQLITE_ROW) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
      ok = text && std::string(text) == "ok";
    }
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return ok;
}

bool sound = false;  // of the current input

void check_sample(const storage::Sample& s) {
  const int status = static_cast<int>(s.status);
  FUZZ_CHECK(status >= 0 && status < storage::kSampleStatusCount);
  if (s.value && sound) FUZZ_CHECK(s.status == SampleStatus::kOk);  // a CHECK constraint of the schema
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
        if (i > 0 && sound) FUZZ_CHECK(samples[i - 1].t_ns <= samples[i].t_ns);
      }
    }
    FUZZ_CHECK(device.period.count() > 0);
    (void)sim::replay_module_options(device, 0);  // does not start a server
    ports.push_back(15020 + static_cast<int>(ports.size()));
  }
  const std::string toml = sim::replay_experiment_toml(recorded, ports, 10.0);
  // Names the store's UNIQUE constraints and the experiment parser guarantee
  // for any run the logger wrote; only a damaged file breaks them, and then
  // the replay may refuse the run (with a message).
  std::set<std::string> device_names;
  std::set<std::string> channel_names;  // unique across devices, as acquisition::channel_name_key compares them
  bool names_sound = true;
  for (const sim::ReplayDevice& device : recorded.devices) {
    names_sound = names_sound && !device.name.empty() && device_names.insert(device.name).second;
    for (const auto& channel : device.channels) {
      names_sound = names_sound && !channel.name.empty() &&
                    channel_names.insert(acquisition::channel_name_key(channel.name)).second;
    }
  }
  // The replay's time scale is the recorded one times its speed (10 here).
  const double replayed_scale = recorded.run.time_scale * 10.0;
  names_sound = names_sound && replayed_scale >= acquisition::kSmallestTimeScale &&
                replayed_scale <= acquisition::kLargestTimeScale;
  try {
    (void)acquisition::parse_experiment(toml, "replay.toml");
  } catch (const std::exception& e) {
    FUZZ_CHECK(e.what()[0] != '\0');
    if (!names_sound || !sound) return;
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
        if (i > 0 && sound) FUZZ_CHECK(samples[i - 1].t_ns <= samples[i].t_ns);
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
  sound = file_is_sound(dir / storage::RunStore::kDatabaseFileName);
  read_through_replay(dir);
  read_through_store(dir);
  return 0;
}
