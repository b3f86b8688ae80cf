// What the logger promises about the records it read (docs/RELIABILITY.md):
// killed at any moment (kill -9) the store is intact and holds everything
// committed, at most the last commit interval is lost, and the next command
// closes the run as interrupted saying what is missing; a clean stop
// (SIGINT, SIGTERM, SIGHUP, --duration) stores every record read, even while
// another connection holds the database; a device call that never returns
// does not hold the stop. `bosfuse acquire` runs as a user runs it, against
// a simulated module on loopback that logs every value it served.

#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <random>

#include "storage/database.h"
#include "tests/support/modbus_fixture.h"
#include "tests/support/subprocess.h"
#include "tests/support/temp_dir.h"

namespace bosfuse {
namespace {

using namespace testing;

using testing::kBosfuse;
constexpr int kChannels = 2;
constexpr std::int64_t kCommitWindowNs = 100'000'000;  // the promise: at most 100 ms lost

class Durability : public ::testing::Test {
 protected:
  void SetUp() override { server_.start(); }

  std::string experiment(double timeout_s = 0.5) {
    std::string toml = "[run]\nname = \"durability\"\n\n" + tcp_device_toml("adam", server_.port(), kChannels, 0.05);
    toml.replace(toml.find("timeout_s = 0.5"), 15, "timeout_s = " + std::to_string(timeout_s));
    const std::string path = (dir_ / ("exp-" + std::to_string(++files_) + ".toml")).string();
    std::ofstream(path) << toml;
    return path;
  }

  BackgroundProcess acquire(const std::string& experiment, const std::string& run, const std::string& extra = "") {
    std::vector<std::string> argv = {kBosfuse, "acquire", experiment, "--out", run};
    if (!extra.empty()) argv.push_back(extra);
    return BackgroundProcess(argv);
  }

  static std::string integrity(const std::string& run) {
    storage::Database db(run + "/run.sqlite", storage::Database::Mode::kReadOnly);
    auto stmt = db.prepare("PRAGMA integrity_check");
    return stmt.step() ? stmt.column_text(0) : "no answer";
  }

  // Served values of channel `c` in the order the module produced them.
  std::vector<sim::ModbusSimServer::ServedValue> served(int c) const {
    std::vector<sim::ModbusSimServer::ServedValue> out;
    for (const auto& v : server_.served()) {
      if (v.channel == c) out.push_back(v);
    }
    return out;
  }

  // Every stored sample is the value served in the same place of the
  // sequence (nothing reordered, duplicated or made up).
  void expect_stored_prefix_of_served(const std::vector<storage::Sample>& stored, int c) const {
    const auto values = served(c);
    ASSERT_LE(stored.size(), values.size());
    for (std::size_t k = 0; k < stored.size(); ++k) {
      ASSERT_TRUE(stored[k].value.has_value()) << "sample " << k;
      ASSERT_NEAR(*stored[k].value, *values[k].reading.value, 1e-9) << "channel " << c << " sample " << k;
    }
  }

  TempDir dir_;
  sim::ModbusSimServer server_{module_options("adam-6018", kChannels, loopback_tcp())};
  int files_ = 0;
};

TEST_F(Durability, KilledAtRandomMomentsLosesAtMostTheCommitWindow) {
  const std::string exp = experiment();
  const unsigned seed = std::random_device{}();
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> kill_after_ms(0, 1200);
  SCOPED_TRACE("seed " + std::to_string(seed));
  for (int round = 0; round < 5; ++round) {
    const std::string run = (dir_ / ("run-" + std::to_string(round))).string();
    const auto served_before = server_.served().size();
    std::int64_t killed_ns = 0;
    {
      auto logger = acquire(exp, run);
      // A random moment while polling (the logger's start-up time varies with the machine's load).
      ASSERT_TRUE(wait_for([&] { return server_.served().size() > served_before; }, 10s)) << "the logger never polled";
      std::this_thread::sleep_for(std::chrono::milliseconds(kill_after_ms(random)));
      killed_ns = acquisition::utc_now_ns();
      logger.send_signal(SIGKILL);
      EXPECT_EQ(logger.wait_exit(5s), -1) << "the logger was not killed";
    }
    SCOPED_TRACE("round " + std::to_string(round));
    ASSERT_EQ(integrity(run), "ok");

    const auto store = storage::RunStore::open(run);  // the next command
    EXPECT_EQ(store.run().status, storage::RunStatus::kInterrupted);
    const auto events = store.events();
    ASSERT_FALSE(events.empty());
    EXPECT_EQ(events.back().kind, "interrupted");
    // A kill within the first commit window leaves nothing recorded, and the event says so.
    const std::string& said = events.back().message;
    EXPECT_TRUE(said.find("the record ends at +") != std::string::npos ||
                said.find("nothing was recorded") != std::string::npos)
        << said;

    const auto stored = samples_by_channel(store);
    for (int c = 0; c < kChannels; ++c) {
      const auto& samples = stored.at("tc" + std::to_string(c));
      std::vector<sim::ModbusSimServer::ServedValue> this_round;
      for (const auto& v : served(c)) {
        if (v.t_ns >= store.run().started_ns) this_round.push_back(v);
      }
      ASSERT_GE(this_round.size(), samples.size());
      for (std::size_t k = 0; k < samples.size(); ++k) {
        ASSERT_NEAR(*samples[k].value, *this_round[k].reading.value, 1e-9) << "channel " << c << " sample " << k;
      }
      if (this_round.size() > samples.size()) {
        const std::int64_t lost_ns = killed_ns - this_round[samples.size()].t_ns;
        EXPECT_LE(lost_ns, kCommitWindowNs) << "channel " << c << " lost " << lost_ns * 1e-6 << " ms of readings";
      }
    }
    EXPECT_GT(server_.served().size(), served_before);
  }
}

TEST_F(Durability, ACleanStopStoresEveryRecordWhileAnotherConnectionHoldsTheStore) {
  const std::string run = (dir_ / "run").string();
  auto logger = acquire(experiment(), run, "--duration=1500ms");
  ASSERT_TRUE(wait_for([&] { return std::filesystem::exists(run + "/run.sqlite"); }, 3s));
  std::this_thread::sleep_for(1200ms);
  {
    // A user's session takes the write lock across the stop, as pandas or
    // the sqlite3 shell may.
    storage::Database other(run + "/run.sqlite", storage::Database::Mode::kReadWrite);
    other.execute("BEGIN IMMEDIATE");
    std::this_thread::sleep_for(800ms);
    other.execute("COMMIT");
  }
  ASSERT_EQ(logger.wait_exit(10s), 0);
  const auto store = storage::RunStore::open(run);
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
  EXPECT_EQ(store.events().back().kind, "stopped");
  const auto stored = samples_by_channel(store);
  for (int c = 0; c < kChannels; ++c) {
    const auto& samples = stored.at("tc" + std::to_string(c));
    EXPECT_EQ(samples.size(), served(c).size()) << "a polled record was not stored";
    expect_stored_prefix_of_served(samples, c);
  }
}

TEST_F(Durability, EveryStopSignalEndsTheRunCleanlyWithEveryRecord) {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE("signal " + std::to_string(signal));
    const std::string run = (dir_ / ("run-" + std::to_string(signal))).string();
    const auto served_before = server_.served().size();
    auto logger = acquire(experiment(), run);
    ASSERT_TRUE(wait_for([&] { return server_.served().size() >= served_before + 10; }, 5s));
    logger.send_signal(signal);
    ASSERT_EQ(logger.wait_exit(5s), 0);
    const auto store = storage::RunStore::open(run);
    EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
    std::size_t stored = 0;
    for (const auto& [name, samples] : samples_by_channel(store)) stored += samples.size();
    EXPECT_EQ(stored, server_.served().size() - served_before) << "a record read before the stop was dropped";
  }
}

// A device that has stopped answering, with a 20 s timeout: Ctrl-C must not
// wait for it.
TEST_F(Durability, AStuckDeviceReadDoesNotHoldTheStop) {
  const std::string run = (dir_ / "run").string();
  auto logger = acquire(experiment(20.0), run);
  ASSERT_TRUE(wait_for([&] { return server_.served().size() >= 4; }, 5s));
  server_.set_silent(true);
  std::this_thread::sleep_for(300ms);  // the next read is now waiting for its 20 s timeout
  const auto stop_requested = std::chrono::steady_clock::now();
  logger.send_signal(SIGINT);
  ASSERT_EQ(logger.wait_exit(5s), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - stop_requested, 1500ms);
  const auto store = storage::RunStore::open(run);
  EXPECT_EQ(store.run().status, storage::RunStatus::kComplete);
  std::vector<std::string> kinds;
  for (const auto& e : store.events()) kinds.push_back(e.kind);
  EXPECT_NE(std::find(kinds.begin(), kinds.end(), "abandoned"), kinds.end());
}

}  // namespace
}  // namespace bosfuse
