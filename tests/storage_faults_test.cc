// What the logger promises when the run store cannot be written
// (docs/RELIABILITY.md): a full disk or a write lock held by another
// connection is said as it happens, costs no CPU while it lasts, and a stop
// under it ends within seconds with the summary, the loss counted and exit
// status 3, never a raw SQL message; the run ends `interrupted` (written
// through the disk reserve, or by the next reader) and what was committed is
// intact. And a disk with too little room is refused before the run starts,
// and one filling up is said before it is full. `bosfuse acquire` runs as
// a user runs it, against a simulated module on loopback, on a tmpfs the
// test mounts (root, as in CI).

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <mutex>
#include <regex>
#include <sstream>
#include <thread>

#include "storage/database.h"
#include "storage/disk_space.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"
#include "tests/support/tmpfs_mount.h"

namespace bosfuse {
namespace {

using namespace testing;

using testing::kBosfuse;
constexpr int kFaultRunChannels = 2;

// User and system CPU time of a process so far, from /proc/PID/stat.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));  // after "pid (comm) "
  std::string field;
  long ticks = 0;
  for (int k = 3; k <= 15 && fields >> field; ++k) {
    if (k == 14 || k == 15) ticks += std::stol(field);  // utime, stime
  }
  return static_cast<double>(ticks) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// The numbers of the summary's "ERROR: N records read were never stored (S samples".
std::pair<long, long> lost_in_summary(const std::string& output) {
  std::smatch match;
  static const std::regex lost(R"(ERROR: (\d+) records read were never stored \((\d+) samples)");
  if (!std::regex_search(output, match, lost)) return {-1, -1};
  return {std::stol(match[1]), std::stol(match[2])};
}

class StorageFaults : public ::testing::Test {
 protected:
  void SetUp() override { server_.start(); }

  std::string experiment(const std::string& run_keys, double period_s) {
    const std::string toml = "[run]\nname = \"faults\"\n" + run_keys + "\n\n" +
                             tcp_device_toml("adam", server_.port(), kFaultRunChannels, period_s);
    const std::string path = (dir_ / ("exp-" + std::to_string(++files_) + ".toml")).string();
    std::ofstream(path) << toml;
    return path;
  }

  // `bosfuse acquire` in the background, its standard output and error in
  // a file beside the test's (never on the disk under test).
  BackgroundProcess acquire(const std::string& experiment, const std::string& run) {
    output_ = (dir_ / ("out-" + std::to_string(++files_) + ".txt")).string();
    return BackgroundProcess(
        {"/bin/sh", "-c", "exec '" + kBosfuse + "' acquire '" + experiment + "' --out '" + run + "' >'" + output_ +
                              "' 2>&1"});
  }

  std::string output() const {
    std::ifstream in(output_);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }

  static std::string integrity(const std::string& run) {
    storage::Database db(run + "/run.sqlite", storage::Database::Mode::kReadOnly);
    auto stmt = db.prepare("PRAGMA integrity_check");
    return stmt.step() ? stmt.column_text(0) : "no answer";
  }

  // Every stored sample is the value served in the same place of the
  // sequence; returns how many are stored.
  std::size_t expect_stored_prefix_of_served(const storage::RunStore& store) const {
    const auto served = server_.served();
    std::size_t stored = 0;
    for (const auto& [name, samples] : samples_by_channel(store)) {
      const int c = std::stoi(name.substr(2));
      std::vector<double> values;
      for (const auto& v : served) {
        if (v.channel == c) values.push_back(*v.reading.value);
      }
      EXPECT_LE(samples.size(), values.size());
      for (std::size_t k = 0; k < samples.size() && k < values.size(); ++k) {
        EXPECT_NEAR(*samples[k].value, values[k], 1e-9) << name << " sample " << k;
      }
      stored += samples.size();
    }
    return stored;
  }

  static std::vector<std::string> event_kinds(const storage::RunStore& store) {
    std::vector<std::string> kinds;
    for (const auto& e : store.events()) kinds.push_back(e.kind);
    return kinds;
  }

  TempDir dir_;
  sim::ModbusSimServer server_{module_options("adam-6018", kFaultRunChannels, loopback_tcp())};
  std::string output_;
  int files_ = 0;
};

std::size_t count_kind(const std::vector<std::string>& kinds, const std::string& kind) {
  return static_cast<std::size_t>(std::count(kinds.begin(), kinds.end(), kind));
}

// The probe's case: a 1 MB disk, polled at 50 Hz, fills within seconds.
TEST_F(StorageFaults, AFullDiskIsSaidCountedAndTheRunClosedInterruptedWithExit3) {
  TmpfsMount disk(dir_ / "disk", "1m");
  const std::string run = (disk / "run").string();
  auto logger = acquire(experiment("min_free_mb = 0", 0.02), run);
  ASSERT_TRUE(wait_for([&] { return output().find("the disk holding the run is full") != std::string::npos; }, 60s))
      << "the full disk was not said\n"
      << output();
  EXPECT_LT(storage::free_bytes(disk.path()), 64u * 1024) << "said full with room left";

  // While the disk is full the logger goes on polling; its commits must back off.
  const double cpu_before = cpu_seconds(logger.pid());
  const auto wall_before = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(3s);
  const double cpu = cpu_seconds(logger.pid()) - cpu_before;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_before).count();
  EXPECT_LE(cpu / wall, 0.10) << "the logger used " << 100 * cpu / wall << " % of a core while the disk was full";

  const auto stop_requested = std::chrono::steady_clock::now();
  logger.send_signal(SIGINT);
  ASSERT_EQ(logger.wait_exit(30s), 3) << output();
  EXPECT_LT(std::chrono::steady_clock::now() - stop_requested, 8s) << "the stop was not bounded";
  const std::string said = output();
  const auto [lost, lost_samples] = lost_in_summary(said);
  EXPECT_GT(lost_samples, 0) << "no loss in the summary\n" << said;
  EXPECT_EQ(lost, lost_samples) << "only samples are lost: the events fit in the reserve";
  EXPECT_EQ(said.find("SQL step failed"), std::string::npos) << said;
  EXPECT_NE(said.find("run store:"), std::string::npos) << "no summary\n" << said;

  // Read while the disk is still full: the run's account fitted in the reserve.
  EXPECT_EQ(integrity(run), "ok");
  const auto store = storage::RunStore::open(run);
  EXPECT_EQ(store.run().status, storage::RunStatus::kInterrupted);
  const auto kinds = event_kinds(store);
  EXPECT_EQ(count_kind(kinds, "store-full"), 1u) << "one event per outage";
  EXPECT_EQ(count_kind(kinds, "stopped"), 1u);
  ASSERT_EQ(count_kind(kinds, "records-lost"), 1u);
  for (const auto& e : store.events()) {
    if (e.kind == "records-lost") {
      EXPECT_EQ(e.message.find(std::to_string(lost_samples) + " samples and 0 frames read were never stored"), 0u)
          << e.message;
    }
  }
  const std::size_t stored = expect_stored_prefix_of_served(store);
  EXPECT_GT(stored, 0u);
  EXPECT_EQ(stored + static_cast<std::size_t>(lost_samples), server_.served().size())
      << "every value read is stored or counted as lost";
}

// Another connection (the sqlite3 shell, pandas) holds the write lock from
// before the stop until after the logger has ended.
TEST_F(StorageFaults, AWriteLockHeldAcrossTheStopEndsItInBoundedTimeWithTheLossCounted) {
  const std::string run = (dir_ / "run").string();
  auto logger = acquire(experiment("", 0.05), run);
  ASSERT_TRUE(wait_for([&] { return server_.served().size() >= 20; }, 10s)) << output();
  storage::Database other(run + "/run.sqlite", storage::Database::Mode::kReadWrite);
  other.execute("BEGIN IMMEDIATE");
  const auto lock_taken = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_for([&] { return output().find("write lock") != std::string::npos; }, 20s))
      << "the held lock was not said\n"
      << output();

  const auto stop_requested = std::chrono::steady_clock::now();
  logger.send_signal(SIGINT);
  ASSERT_EQ(logger.wait_exit(30s), 3) << output();
  EXPECT_LT(std::chrono::steady_clock::now() - stop_requested, 8s) << "the stop waited for the lock";
  const std::string said = output();
  const auto [lost, lost_samples] = lost_in_summary(said);
  EXPECT_GT(lost_samples, 0) << said;
  EXPECT_GE(lost, lost_samples);
  EXPECT_NE(said.find("the run's status could not be written"), std::string::npos) << said;
  EXPECT_EQ(said.find("SQL step failed"), std::string::npos) << said;
  // The probe's case: a lock of 40 s, which outlives the logger.
  std::this_thread::sleep_until(lock_taken + 40s);
  other.execute("COMMIT");

  // The next reader closes the run its logger could not.
  const auto store = storage::RunStore::open(run);
  EXPECT_EQ(store.run().status, storage::RunStatus::kInterrupted);
  const auto events = store.events();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().kind, "interrupted");
  EXPECT_NE(events.back().message.find("the record ends at +"), std::string::npos) << events.back().message;
  EXPECT_EQ(integrity(run), "ok");
  const std::size_t stored = expect_stored_prefix_of_served(store);
  EXPECT_EQ(stored + static_cast<std::size_t>(lost_samples), server_.served().size())
      << "every value read is stored or counted as lost";
}

TEST_F(StorageFaults, TooLittleFreeSpaceRefusesTheStartNamingTheKey) {
  TmpfsMount disk(dir_ / "small", "1m");
  const std::string run = (disk / "run").string();
  const auto start = [&](const std::string& experiment) {
    return run_command("'" + kBosfuse + "' acquire '" + experiment + "' --out '" + run + "' --duration 600ms");
  };
  const std::string two_mb = experiment("min_free_mb = 2", 0.05);
  auto result = start(two_mb);
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find(two_mb + ":3: run.min_free_mb: the disk of '" + run), std::string::npos)
      << result.output;
  EXPECT_NE(result.output.find("less than the 2 MB asked for"), std::string::npos) << result.output;
  EXPECT_FALSE(std::filesystem::exists(run)) << "the check comes before the run is made";

  result = start(experiment("", 0.05));
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("run.min_free_mb (default 100)"), std::string::npos) << result.output;
  EXPECT_FALSE(std::filesystem::exists(run));

  result = start(experiment("min_free_mb = 0", 0.05));
  EXPECT_EQ(result.exit_code, 0) << "0 turns the check off\n" << result.output;
  EXPECT_EQ(storage::RunStore::open(run).run().status, storage::RunStatus::kComplete);
}

TEST_F(StorageFaults, ALeastFreeSpaceNoDiskHasIsRefusedAnywhere) {
  const std::string run = (dir_ / "run").string();
  const std::string huge = experiment("min_free_mb = 1099511627776", 0.05);
  const auto result = run_command("'" + kBosfuse + "' acquire '" + huge + "' --out '" + run + "' --duration 600ms");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find(huge + ":3: run.min_free_mb"), std::string::npos) << result.output;
  EXPECT_FALSE(std::filesystem::exists(run));
}

// A file grows on the run's disk at 5 MB/s while the logger records: the
// logger says so, with the time left, and says again when it has room.
TEST_F(StorageFaults, AFillingDiskIsSaidBeforeItIsFullWithTheTimeLeft) {
  TmpfsMount disk(dir_ / "filling", "24m");
  const std::string toml = tcp_device_toml("adam", server_.port(), kFaultRunChannels, 0.05);
  auto store = storage::RunStore::create(disk / "run", run_info(toml), storage::RunStore::CreateMode::kNew);
  acquisition::LoggerOptions options;
  options.duration = 3s;
  options.disk_check_interval = 100ms;
  options.disk.min_free_bytes = 0;
  options.disk.warn_within = 20s;  // the filler's 5 MB/s, not the run's own growth on a 24 MB disk
  std::mutex mutex;
  std::vector<std::string> warnings;
  options.on_disk_warning = [&](const std::string& line) {
    std::lock_guard lock(mutex);
    warnings.push_back(line);
  };
  acquisition::Logger logger(store, options);
  logger.add_devices(acquisition::parse_experiment(toml, "exp.toml"));
  std::thread filler([&] {
    const std::string chunk(512 * 1024, 'x');
    {
      std::ofstream out(disk / "filler", std::ios::binary);
      for (int k = 0; k < 16; ++k) {
        out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        out.flush();
        std::this_thread::sleep_for(100ms);
      }
    }
    std::filesystem::remove(disk / "filler");
  });
  std::atomic<bool> stop{false};
  const auto summary = logger.run(stop);
  filler.join();
  EXPECT_TRUE(summary.complete());
  std::lock_guard lock(mutex);
  ASSERT_EQ(warnings.size(), 2u) << "said once when it began, once when it ended";
  EXPECT_NE(warnings[0].find("MB/s: full in about"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find("room again"), std::string::npos) << warnings[1];
  const auto kinds = event_kinds(store);
  EXPECT_EQ(count_kind(kinds, "disk-low"), 1u);
  EXPECT_EQ(count_kind(kinds, "disk-ok"), 1u);
}

}  // namespace
}  // namespace bosfuse
