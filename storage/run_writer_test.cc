// The writer's promises at a stop: everything pushed before stop() is
// committed, also what arrived while a slow commit was running, and what
// arrives after the end is counted, never silently dropped.

#include "storage/run_writer.h"

#include <gtest/gtest.h>

#include <future>
#include <thread>

#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

using namespace std::chrono_literals;

struct Fixture {
  testing::TempDir dir;
  RunStore store = RunStore::create(dir.path() / "run", {0, "t", 0, {}, "", RunStatus::kRunning, 1.0, std::nullopt},
                                    RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
  std::int64_t channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});

  Sample sample(std::int64_t t_ns) const { return {channel, t_ns, {}, 20.0, {}, SampleStatus::kOk}; }
  std::size_t stored() const { return RunStore::open(dir.path() / "run").read_samples(channel).size(); }
};

// Another connection (a user's pandas session, say) holds the write lock
// while the logger stops: the commit in flight waits, more records arrive
// meanwhile, and all of them must be stored.
TEST(RunWriter, StopCommitsWhatArrivedDuringASlowCommit) {
  Fixture f;
  Database other((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
  RunWriter writer(f.store, {10ms, 100'000});
  other.execute("BEGIN IMMEDIATE");
  for (int i = 0; i < 100; ++i) writer.push(f.sample(i));
  std::this_thread::sleep_for(100ms);  // the writer took the first batch and waits for the lock
  for (int i = 100; i < 300; ++i) writer.push(f.sample(i));
  auto stopped = std::async(std::launch::async, [&] { writer.stop(); });
  std::this_thread::sleep_for(100ms);
  other.execute("COMMIT");
  stopped.get();
  const auto stats = writer.stats();
  EXPECT_EQ(stats.uncommitted_at_stop, 0) << stats.last_error;
  EXPECT_EQ(stats.samples_committed, 300);
  EXPECT_EQ(f.stored(), 300u);
}

TEST(RunWriter, RecordsPushedAfterTheEndAreCountedAsUncommitted) {
  Fixture f;
  RunWriter writer(f.store, {10ms, 100'000});
  writer.push(f.sample(1));
  writer.stop();
  writer.push(f.sample(2));
  writer.push(Event{0, std::nullopt, 3, "late", "after the end"});
  const auto stats = writer.stats();
  EXPECT_EQ(stats.samples_committed, 1);
  EXPECT_EQ(stats.uncommitted_at_stop, 2);
  EXPECT_NE(stats.last_error.find("after the writer had stopped"), std::string::npos);
}

TEST(RunWriter, EveryCommitMarksTheRunAlive) {
  Fixture f;
  {
    RunWriter writer(f.store, {10ms, 100'000});
    writer.push(f.sample(1));
    writer.flush();
  }
  Database db((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadOnly);
  auto stmt = db.prepare("SELECT alive_ns FROM runs");
  ASSERT_TRUE(stmt.step());
  ASSERT_TRUE(stmt.column_optional_int64(0).has_value()) << "no heartbeat after a commit";
  EXPECT_GT(*stmt.column_optional_int64(0), 1'600'000'000'000'000'000);
}

}  // namespace
}  // namespace bosfuse::storage
