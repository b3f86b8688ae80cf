// The writer's promises at a stop: everything pushed before stop() is
// committed, also what arrived while a slow commit was running, and what
// arrives after the end is counted, never silently dropped. And its
// promises about a store that cannot be written: one outage is said once
// and once when it ends, retried with backoff, bounded in memory (the rest
// dropped and counted), and a stop stays bounded in time.

#include "storage/run_writer.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <atomic>
#include <future>
#include <thread>

#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

using namespace std::chrono_literals;

struct RunWriterFixture {
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
  RunWriterFixture f;
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
  RunWriterFixture f;
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
  RunWriterFixture f;
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

// A store that fails on demand, with the result code SQLite gives for the
// fault, else writes into a real run store. Empty writes touch nothing, as
// in RunStore.
class FailingSink : public RunWriter::Sink {
 public:
  explicit FailingSink(RunStore& store) : store_(store) {}

  void fail_with(int sqlite_code) { code_ = sqlite_code; }  // 0: works again
  // Fails with SQLITE_FULL while the run's reserve file is there, as a
  // full disk does once the reserve's room is free.
  void full_until_the_reserve_is_spent() { full_until_reserve_spent_ = true; }
  int attempts() const { return attempts_; }

  void write_events(std::span<const Event> events) override {
    if (attempt(events.size())) store_.write_events(events);
  }
  void write_frames(std::span<const FrameRecord> frames) override {
    if (attempt(frames.size())) store_.write_frames(frames);
  }
  void write_samples(std::span<const Sample> samples) override {
    if (attempt(samples.size())) store_.write_samples(samples);
  }
  void mark_alive(std::int64_t t_ns) override {
    if (attempt(1)) store_.mark_alive(t_ns);
  }
  void finish(RunStatus status, std::int64_t ended_ns) override {
    if (attempt(1)) store_.finish(status, ended_ns);
  }
  void give_up_lock_waits_at(std::chrono::steady_clock::time_point deadline) override {
    store_.give_up_lock_waits_at(deadline);
  }
  std::filesystem::path dir() const override { return store_.dir(); }

 private:
  bool attempt(std::size_t count) {
    if (count == 0) return false;
    ++attempts_;
    int code = code_;
    if (full_until_reserve_spent_ && std::filesystem::exists(store_.dir() / SpaceReserve::kFileName)) code = SQLITE_FULL;
    if (code != 0) throw StorageError(std::string("SQL step failed in (INSERT ...): ") + sqlite3_errstr(code), code);
    return true;
  }

  RunStore& store_;
  std::atomic<int> code_{0};
  std::atomic<bool> full_until_reserve_spent_{false};
  std::atomic<int> attempts_{0};
};

// Warnings as the writer says them, from its thread.
struct Warnings {
  std::vector<std::string> lines() const {
    std::lock_guard lock(mutex);
    return said;
  }
  std::size_t count_of(const std::string& words) const {
    std::size_t n = 0;
    for (const auto& line : lines()) n += line.find(words) != std::string::npos;
    return n;
  }
  std::function<void(const std::string&)> sink() {
    return [this](const std::string& line) {
      std::lock_guard lock(mutex);
      said.push_back(line);
    };
  }
  mutable std::mutex mutex;
  std::vector<std::string> said;
};

RunWriterOptions fault_options(Warnings& warnings) {
  RunWriterOptions options;
  options.flush_interval = 5ms;
  options.retry_initial = 20ms;
  options.retry_max = 160ms;
  options.stop_timeout = 500ms;
  options.on_fault = warnings.sink();
  return options;
}

std::vector<std::string> event_kinds(const RunStore& store) {
  std::vector<std::string> kinds;
  for (const auto& e : store.events()) kinds.push_back(e.kind);
  return kinds;
}

std::size_t count(const std::vector<std::string>& kinds, const std::string& kind) {
  return static_cast<std::size_t>(std::count(kinds.begin(), kinds.end(), kind));
}

// The probe found about 16,500 retries in 3 s on a full disk: each commit
// failed and was tried again at once. Now: one warning and one event when
// the disk fills, retries 20, 40, 80, 160, 160 ms ... apart, and one of
// each again when it has room.
TEST(RunWriter, AFullDiskIsOneOutageSaidOnceRetriedWithBackoffAndSaidWhenItEnds) {
  RunWriterFixture f;
  FailingSink sink(f.store);
  Warnings warnings;
  RunWriter writer(sink, fault_options(warnings));
  sink.fail_with(SQLITE_FULL);
  const auto start = std::chrono::steady_clock::now();
  int pushed = 0;
  while (std::chrono::steady_clock::now() - start < 1500ms) {
    writer.push(f.sample(pushed++));
    std::this_thread::sleep_for(2ms);
  }
  const int attempts_while_full = sink.attempts();
  // 1.5 s of backoff capped at 160 ms is 12 tries or so; a writer that
  // retried at each flush interval or at once would make hundreds.
  EXPECT_GE(attempts_while_full, 4) << "the commit was not retried";
  EXPECT_LE(attempts_while_full, 25) << "retries did not back off";
  EXPECT_EQ(warnings.count_of("the disk holding the run is full (database or disk is full)"), 1u);
  EXPECT_EQ(warnings.lines().size(), 1u) << "an outage is said once, not per retry";
  EXPECT_EQ(writer.stats().outages, 1);
  EXPECT_NE(writer.stats().last_error.find("disk holding the run is full"), std::string::npos);

  sink.fail_with(0);
  ASSERT_TRUE([&] {
    for (int i = 0; i < 100 && writer.stats().samples_committed < pushed; ++i) std::this_thread::sleep_for(20ms);
    return writer.stats().samples_committed == pushed;
  }()) << "the queued records were not committed once the disk had room";
  writer.close_run(1);
  const auto stats = writer.stats();
  EXPECT_EQ(stats.lost(), 0);
  EXPECT_TRUE(stats.status_written);
  EXPECT_EQ(warnings.count_of("the run store is written again after"), 1u);
  const auto reader = RunStore::open(f.dir.path() / "run");
  EXPECT_EQ(reader.read_samples(f.channel).size(), static_cast<std::size_t>(pushed));
  const auto kinds = event_kinds(reader);
  EXPECT_EQ(count(kinds, "store-full"), 1u);
  EXPECT_EQ(count(kinds, "store-recovered"), 1u);
  EXPECT_EQ(reader.run().status, RunStatus::kComplete);
}

TEST(RunWriter, EachStorageFaultIsAnEventOfItsOwnKind) {
  const std::vector<std::pair<int, std::string>> faults = {
      {SQLITE_FULL, "store-full"}, {SQLITE_IOERR_WRITE, "store-io-error"}, {SQLITE_BUSY, "store-locked"},
      {SQLITE_CORRUPT, "store-error"}};
  for (const auto& [code, kind] : faults) {
    SCOPED_TRACE(kind);
    RunWriterFixture f;
    FailingSink sink(f.store);
    Warnings warnings;
    {
      RunWriter writer(sink, fault_options(warnings));
      sink.fail_with(code);
      writer.push(f.sample(1));
      writer.flush();
      sink.fail_with(0);
      writer.flush();  // the outage's event goes first
      writer.flush();
      writer.close_run(2);
      EXPECT_EQ(writer.stats().lost(), 0);
    }
    const auto kinds = event_kinds(RunStore::open(f.dir.path() / "run"));
    EXPECT_EQ(count(kinds, kind), 1u);
    EXPECT_EQ(count(kinds, "store-recovered"), 1u);
    ASSERT_EQ(warnings.lines().size(), 2u);
  }
}

// The queue's bound: what does not fit is dropped and counted, said once,
// and the count is an event of the run once the store takes records again.
TEST(RunWriter, BeyondTheQueuesBoundRecordsAreDroppedAndCounted) {
  RunWriterFixture f;
  FailingSink sink(f.store);
  Warnings warnings;
  auto options = fault_options(warnings);
  options.max_queued_bytes = 100 * sizeof(Sample);
  RunWriter writer(sink, options);
  sink.fail_with(SQLITE_FULL);
  writer.push(f.sample(0));
  writer.flush();  // the outage has begun: its event takes some of the room
  for (int i = 1; i <= 250; ++i) writer.push(f.sample(i));
  const std::int64_t dropped = writer.stats().dropped_queue_full;
  // 100 samples' room, less the store-full event's (a few samples' worth).
  EXPECT_GE(dropped, 151);
  EXPECT_LE(dropped, 171);
  EXPECT_EQ(writer.stats().samples_lost, dropped);
  ASSERT_TRUE([&] {
    for (int i = 0; i < 50 && warnings.count_of("new records are dropped, and counted") == 0; ++i) {
      std::this_thread::sleep_for(20ms);
    }
    return warnings.count_of("new records are dropped, and counted") == 1;
  }()) << "the drops were not said";
  sink.fail_with(0);
  for (int i = 0; i < 100 && writer.stats().samples_committed < 251 - dropped; ++i) std::this_thread::sleep_for(20ms);
  writer.close_run(1);
  const auto stats = writer.stats();
  EXPECT_EQ(stats.samples_committed + stats.dropped_queue_full, 251) << "every record stored or counted";
  EXPECT_EQ(stats.lost(), dropped);
  const auto reader = RunStore::open(f.dir.path() / "run");
  EXPECT_EQ(reader.run().status, RunStatus::kInterrupted) << "a run that lost records is not complete";
  bool counted = false;
  for (const auto& e : reader.events()) {
    if (e.kind == "records-dropped") counted = e.message.find(std::to_string(dropped) + " records") == 0;
  }
  EXPECT_TRUE(counted) << "no records-dropped event with the count";
}

// Another connection holds the write lock across the stop: the commit in
// flight gives up at the stop's deadline, whatever the lock timeout, and
// the loss is counted.
TEST(RunWriter, AStopUnderALockThatIsNotReleasedIsBoundedAndCountsTheLoss) {
  RunWriterFixture f;
  Database other((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
  Warnings warnings;
  auto options = fault_options(warnings);
  RunWriter writer(f.store, options);
  other.execute("BEGIN IMMEDIATE");
  for (int i = 0; i < 50; ++i) writer.push(f.sample(i));
  std::this_thread::sleep_for(100ms);  // the writer waits for the lock (for up to 5 s)
  const auto stopping = std::chrono::steady_clock::now();
  writer.close_run(1);
  const auto took = std::chrono::steady_clock::now() - stopping;
  EXPECT_LT(took, options.stop_timeout + RunWriter::kStatusLockWait + 1s) << "the stop waited for the lock";
  const auto stats = writer.stats();
  EXPECT_EQ(stats.samples_lost, 50);
  EXPECT_FALSE(stats.status_written);
  EXPECT_NE(stats.status_error.find("locked"), std::string::npos) << stats.status_error;
  other.execute("COMMIT");
  EXPECT_TRUE(RunStore::open(f.dir.path() / "run").read_samples(f.channel).empty());
}

// At a stop on a full disk the run's reserve is deleted, and its room
// takes the run's account: the outage, the loss and the status.
TEST(RunWriter, AtAStopOnAFullDiskTheReserveTakesTheRunsAccount) {
  RunWriterFixture f;
  FailingSink sink(f.store);
  Warnings warnings;
  RunWriter writer(sink, fault_options(warnings));
  ASSERT_TRUE(std::filesystem::exists(f.dir.path() / "run" / SpaceReserve::kFileName));
  sink.full_until_the_reserve_is_spent();
  for (int i = 0; i < 30; ++i) writer.push(f.sample(i));
  writer.flush();
  writer.push(Event{0, std::nullopt, 40, "stopped", "stop requested"});
  writer.close_run(50);
  const auto stats = writer.stats();
  EXPECT_TRUE(stats.reserve_released);
  EXPECT_EQ(stats.samples_lost, 30);
  EXPECT_EQ(stats.lost(), 30) << "the events were stored in the reserve's room";
  EXPECT_TRUE(stats.status_written);
  EXPECT_FALSE(std::filesystem::exists(f.dir.path() / "run" / SpaceReserve::kFileName));
  const auto reader = RunStore::open(f.dir.path() / "run");
  EXPECT_EQ(reader.run().status, RunStatus::kInterrupted);
  const auto events = reader.events();
  const auto kinds = event_kinds(reader);
  EXPECT_EQ(count(kinds, "store-full"), 1u);
  EXPECT_EQ(count(kinds, "stopped"), 1u);
  ASSERT_EQ(count(kinds, "records-lost"), 1u);
  for (const auto& e : events) {
    if (e.kind == "records-lost") {
      EXPECT_EQ(e.message.find("30 samples and 0 frames read were never stored"), 0u) << e.message;
    }
  }
}

TEST(RunWriter, AReserveIsKeptWhileTheRunIsRecordedAndGoneAfter) {
  RunWriterFixture f;
  const auto reserve = f.dir.path() / "run" / SpaceReserve::kFileName;
  {
    RunWriter writer(f.store, {10ms, 100'000});
    ASSERT_TRUE(std::filesystem::exists(reserve));
    EXPECT_EQ(std::filesystem::file_size(reserve), RunWriterOptions{}.reserve_bytes);
    writer.close_run(1);
    EXPECT_FALSE(std::filesystem::exists(reserve));
  }
  RunWriterOptions none;
  none.reserve_bytes = 0;
  RunWriter writer(f.store, none);
  EXPECT_FALSE(std::filesystem::exists(reserve));
}

}  // namespace
}  // namespace bosfuse::storage
