#include "storage/run_store.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "storage/processing_store.h"
#include "storage/record_rows.h"
#include "storage/run_tail.h"
#include "storage/run_writer.h"
#include "storage/schema.h"
#include "storage/transaction.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

RunInfo test_run() {
  RunInfo info;
  info.name = "cooling-test";
  info.started_ns = 1'700'000'000'000'000'000;
  info.config_toml = "[run]\nname = \"cooling-test\"\n";
  return info;
}

struct RunStoreFixture {
  testing::TempDir dir;
  RunStore store = RunStore::create(dir.path() / "run", test_run(), RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", "127.0.0.1:502"});
  std::int64_t channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", 120.5, 80.0});
};

TEST(RunStore, CreatesARunAndReadsItBack) {
  RunStoreFixture f;
  const RunInfo run = f.store.run();
  EXPECT_EQ(run.name, "cooling-test");
  EXPECT_EQ(run.status, RunStatus::kRunning);
  EXPECT_EQ(run.config_toml, test_run().config_toml);
  ASSERT_EQ(f.store.channels().size(), 1u);
  EXPECT_EQ(f.store.channels()[0].tc_type, "K");
  EXPECT_DOUBLE_EQ(*f.store.channels()[0].image_x_px, 120.5);
  f.store.finish(RunStatus::kComplete, run.started_ns + 5);
  EXPECT_EQ(f.store.run().status, RunStatus::kComplete);
  EXPECT_EQ(f.store.run().ended_ns, run.started_ns + 5);
}

TEST(RunStore, BatchedInsertAndRangeRead) {
  RunStoreFixture f;
  std::vector<Sample> samples;
  for (int i = 0; i < 10'000; ++i) {
    samples.push_back({f.channel, 1'000 + i * 10, std::nullopt, 20.0 + i * 0.001, std::nullopt, SampleStatus::kOk});
  }
  f.store.write_samples(samples);
  const auto all = f.store.read_samples(f.channel);
  ASSERT_EQ(all.size(), samples.size());
  EXPECT_DOUBLE_EQ(*all.back().value, *samples.back().value);
  const auto part = f.store.read_samples(f.channel, {1'000 + 100 * 10, 1'000 + 199 * 10});
  ASSERT_EQ(part.size(), 100u);
  EXPECT_EQ(part.front().t_ns, 2'000);
  EXPECT_EQ(part.back().t_ns, 2'990);
}

TEST(RunStore, NonOkSamplesStoreNoValue) {
  RunStoreFixture f;
  const std::vector<Sample> samples = {{f.channel, 1, std::nullopt, 999.0, 65535.0, SampleStatus::kOpenCircuit},
                                       {f.channel, 2, std::nullopt, std::nullopt, std::nullopt, SampleStatus::kTimeout},
                                       {f.channel, 3, 77, 25.0, 1200.0, SampleStatus::kOk}};
  f.store.write_samples(samples);
  const auto read = f.store.read_samples(f.channel);
  ASSERT_EQ(read.size(), 3u);
  EXPECT_EQ(read[0].status, SampleStatus::kOpenCircuit);
  EXPECT_FALSE(read[0].value.has_value()) << "a burnt-out thermocouple was stored as a temperature";
  EXPECT_EQ(read[0].raw, 65535.0);
  EXPECT_EQ(read[1].status, SampleStatus::kTimeout);
  EXPECT_EQ(read[2].device_t_ns, 77);
  EXPECT_EQ(read[2].value, 25.0);
}

TEST(RunStore, SampleColumnsHoldTheSamplesInTimeOrderWithNaNForNoValue) {
  RunStoreFixture f;
  const std::vector<Sample> samples = {{f.channel, 9, std::nullopt, 21.0, std::nullopt, SampleStatus::kOk},
                                       {f.channel, 3, std::nullopt, std::nullopt, 65535.0, SampleStatus::kOpenCircuit},
                                       {f.channel, 5, 77, 25.0, 1200.0, SampleStatus::kOk}};
  f.store.write_samples(samples);
  const auto records = f.store.read_samples(f.channel);
  const SampleColumns columns = f.store.read_sample_columns(f.channel);
  ASSERT_EQ(columns.t_ns.size(), records.size());
  ASSERT_EQ(columns.value.size(), records.size());
  ASSERT_EQ(columns.status.size(), records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(columns.t_ns[i], records[i].t_ns) << i;
    EXPECT_EQ(columns.status[i], records[i].status) << i;
    if (records[i].value) {
      EXPECT_EQ(columns.value[i], *records[i].value) << i;
    } else {
      EXPECT_TRUE(std::isnan(columns.value[i])) << "a sample without a value read as " << columns.value[i];
    }
  }
  EXPECT_EQ(columns.t_ns, (std::vector<std::int64_t>{3, 5, 9}));
}

TEST(RunStore, FolderHoldingARunIsRefusedUnlessAppending) {
  testing::TempDir dir;
  {
    auto store = RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kNew);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    const Sample s{channel, 10, {}, 30.0, {}, SampleStatus::kOk};
    store.write_samples({&s, 1});
    store.finish(RunStatus::kComplete, 20);
  }
  EXPECT_THROW(RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kNew), StorageError);
  auto appended = RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kAppend);
  EXPECT_EQ(appended.run().status, RunStatus::kRunning);
  const auto device = appended.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
  const auto channel = appended.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
  EXPECT_EQ(appended.channels().size(), 1u) << "appending duplicated the channel";
  EXPECT_EQ(appended.read_samples(channel).size(), 1u) << "appending lost committed samples";
  ASSERT_EQ(appended.events().size(), 1u);
  EXPECT_EQ(appended.events()[0].kind, "appended");
}

TEST(RunStore, ASecondLoggerIsKeptOutOfARunBeingRecorded) {
  RunStoreFixture f;
  try {
    RunStore::create(f.dir.path() / "run", test_run(), RunStore::CreateMode::kAppend);
    FAIL() << "two loggers were let into one run";
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find("being recorded by another logger (pid "), std::string::npos) << e.what();
  }
}

TEST(RunStore, AppendingWithADifferentExperimentFileIsRefusedNamingTheLine) {
  testing::TempDir dir;
  RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kNew).finish(RunStatus::kComplete, 5);
  RunInfo other = test_run();
  other.config_toml = "[run]\nname = \"another\"\n";
  try {
    RunStore::create(dir / "run", other, RunStore::CreateMode::kAppend);
    FAIL() << "a run was continued with another experiment file";
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2: `name = \"cooling-test\"` became `name = \"another\"`"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(RunStore::open(dir / "run").run().status, RunStatus::kComplete) << "the refused append changed the run";
}

// A logger that dies leaves its run `running` with nobody holding the lock:
// the next open closes it as interrupted and says what is missing.
TEST(RunStore, ARunWhoseLoggerDiedIsClosedAsInterruptedByTheNextOpen) {
  testing::TempDir dir;
  const RunInfo info = test_run();
  {
    auto store = RunStore::create(dir / "run", info, RunStore::CreateMode::kNew);
    store.set_planned_end(info.started_ns + 60'000'000'000);
    const auto device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", ""});
    const auto channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", {}, {}});
    const Sample s{channel, info.started_ns + 12'000'000'000, {}, 30.0, {}, SampleStatus::kOk};
    store.write_samples({&s, 1});
    store.mark_alive(info.started_ns + 12'050'000'000);
    // The store goes away without finish(): as if the logger was killed.
  }
  const auto store = RunStore::open(dir / "run");
  const RunInfo run = store.run();
  EXPECT_EQ(run.status, RunStatus::kInterrupted);
  EXPECT_EQ(run.ended_ns, info.started_ns + 12'050'000'000);
  const auto events = store.events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, "interrupted");
  EXPECT_NE(events[0].message.find("the record ends at +12.000 s"), std::string::npos) << events[0].message;
  EXPECT_NE(events[0].message.find("last alive at +12.050 s"), std::string::npos) << events[0].message;
  EXPECT_NE(events[0].message.find("47.950 s of the planned 60.000 s are missing"), std::string::npos)
      << events[0].message;
  EXPECT_EQ(RunStore::open(dir / "run").events().size(), 1u) << "a second open recorded the interruption again";
}

// Opening for reading checks the schema version as opening for writing
// always did: a store from a newer bosfuse is refused by every way in
// (RunStore, ProcessingStore, RunTail), even a `running` one whose logger
// died, which an open would otherwise close, so the refusal writes nothing.
TEST(RunStore, EveryOpeningRefusesAStoreFromANewerBosfuse) {
  testing::TempDir dir;
  { RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kNew); }  // left running, as if killed
  {
    Database db(database_path(dir / "run"), Database::Mode::kReadWrite);
    db.execute("INSERT INTO schema_version (version, applied_ns) VALUES (" + std::to_string(kSchemaVersion + 1) +
               ", 0)");
  }
  const auto expect_refused = [](const std::function<void()>& open, const char* what) {
    try {
      open();
      ADD_FAILURE() << what << " read a store from a newer bosfuse";
    } catch (const StorageError& e) {
      EXPECT_NE(std::string(e.what()).find("newer than this bosfuse understands"), std::string::npos) << e.what();
    }
  };
  expect_refused([&] { RunStore::open(dir / "run"); }, "RunStore::open");
  expect_refused([&] { RunStore::open(dir / "run", true); }, "RunStore::open(writable)");
  expect_refused([&] { ProcessingStore(dir / "run"); }, "ProcessingStore");
  expect_refused([&] { ProcessingStore(dir / "run", true); }, "ProcessingStore(writable)");
  expect_refused([&] { RunTail tail(dir / "run"); }, "RunTail");
  expect_refused([&] { RunStore::create(dir / "run", test_run(), RunStore::CreateMode::kAppend); }, "appending");
  Database db(database_path(dir / "run"), Database::Mode::kReadOnly);
  auto status = db.prepare("SELECT status FROM runs");
  ASSERT_TRUE(status.step());
  EXPECT_EQ(status.column_text(0), "running") << "a refused store was closed as interrupted";
  EXPECT_FALSE(db.prepare("SELECT 1 FROM events").step()) << "a refused store was written to";
}

TEST(RunStore, ARunBeingRecordedIsLeftRunning) {
  RunStoreFixture f;
  EXPECT_EQ(RunStore::open(f.dir.path() / "run").run().status, RunStatus::kRunning);
  EXPECT_TRUE(RunStore::open(f.dir.path() / "run").events().empty());
}

// Found by fuzzing: a forged store (foreign keys off) held a status code
// no SampleStatus has, and reading it was undefined behaviour.
TEST(RunStore, ASampleWithAnUnknownStatusCodeIsRefusedAsDamage) {
  RunStoreFixture f;
  {
    Database db((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
    db.execute("PRAGMA foreign_keys = OFF");
    db.execute("INSERT INTO samples (channel_id, t_ns, value, status) VALUES (" + std::to_string(f.channel) +
               ", 5, NULL, 77)");
  }
  try {
    f.store.read_samples(f.channel);
    FAIL() << "an unknown status code was read";
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find("status code 77"), std::string::npos) << e.what();
  }
}

// Found by fuzzing: a store whose schema text was damaged no longer had the
// CHECK that only an ok sample has a value; such a sample is refused.
TEST(RunStore, ASampleWithAValueAndAFailedStatusIsRefusedAsDamage) {
  RunStoreFixture f;
  {
    Database db((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
    db.execute("PRAGMA ignore_check_constraints = ON");
    db.execute("INSERT INTO samples (channel_id, t_ns, value, status) VALUES (" + std::to_string(f.channel) +
               ", 5, 21.5, " + std::to_string(static_cast<int>(SampleStatus::kTimeout)) + ")");
  }
  for (const bool as_columns : {false, true}) {
    try {
      if (as_columns) {
        f.store.read_sample_columns(f.channel);
      } else {
        f.store.read_samples(f.channel);
      }
      FAIL() << "a timed-out sample with a value was read" << (as_columns ? " as columns" : "");
    } catch (const StorageError& e) {
      EXPECT_NE(std::string(e.what()).find("has status timeout and a value"), std::string::npos) << e.what();
    }
  }
}

TEST(RunStore, OpeningAFolderWithoutARunSaysSo) {
  testing::TempDir dir;
  try {
    RunStore::open(dir.path());
    FAIL();
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no bosfuse run"), std::string::npos);
  }
}

TEST(RunStore, FramesAndEventsRoundTrip) {
  RunStoreFixture f;
  f.store.add_frame({0, std::nullopt, 500, 499, "frames/000001.png", 640, 480, 16, true});
  f.store.add_frame({0, std::nullopt, 400, std::nullopt, "frames/000000.png", 640, 480, 16, false});
  const auto frames = f.store.frames();
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].t_ns, 400);
  EXPECT_TRUE(frames[1].is_reference);
  EXPECT_EQ(frames[1].bit_depth, 16);
  const std::vector<Event> events = {{0, f.device, 10, "disconnect", "timed out"}, {0, std::nullopt, 5, "started", ""}};
  f.store.write_events(events);
  const auto read = f.store.events();
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[0].kind, "started");
  EXPECT_EQ(read[1].device_id, f.device);
}

TEST(Transaction, RollsBackUnlessCommitted) {
  RunStoreFixture f;
  Database db((f.dir.path() / "run" / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
  {
    Transaction t(db);
    db.execute("INSERT INTO events (run_id, t_ns, kind, message) VALUES (1, 1, 'error', 'never committed')");
  }
  EXPECT_TRUE(f.store.events().empty());
}

TEST(RunWriter, CommitsEverythingPushedFromManyThreads) {
  RunStoreFixture f;
  const auto second = f.store.add_channel({0, f.device, "tc1", "thermocouple", "degC", "K", {}, {}});
  constexpr int kPerThread = 20'000;
  {
    RunWriter writer(f.store, {std::chrono::milliseconds(20), 5'000});
    auto produce = [&](std::int64_t channel) {
      for (int i = 0; i < kPerThread; ++i) writer.push(Sample{channel, i, {}, double(i), {}, SampleStatus::kOk});
    };
    std::thread a(produce, f.channel), b(produce, second);
    a.join();
    b.join();
    writer.push(Event{0, {}, 1, "stopped", "end of test"});
    writer.flush();
    EXPECT_EQ(writer.stats().samples_committed, 2 * kPerThread);
    EXPECT_EQ(writer.stats().failed_commits, 0);
  }
  for (auto channel : {f.channel, second}) {
    const auto samples = f.store.read_samples(channel);
    ASSERT_EQ(samples.size(), std::size_t(kPerThread));
    for (int i = 0; i < kPerThread; ++i) ASSERT_EQ(samples[i].value, double(i));
  }
  EXPECT_EQ(f.store.events().size(), 1u);
}

TEST(RunWriter, AFailedCommitKeepsTheBatchAndRetries) {
  RunStoreFixture f;
  RunWriter writer(f.store, {std::chrono::milliseconds(10), 1'000});
  // A sample for a channel that does not exist violates the foreign key:
  // its batch must fail without losing the good samples queued with it.
  const std::vector<Sample> batch = {{f.channel, 1, {}, 1.0, {}, SampleStatus::kOk},
                                     {9999, 2, {}, 2.0, {}, SampleStatus::kOk}};
  writer.push(batch);  // one push: the two can only be committed together
  writer.flush();
  EXPECT_GE(writer.stats().failed_commits, 1);
  EXPECT_NE(writer.stats().last_error.find("FOREIGN KEY"), std::string::npos) << writer.stats().last_error;
  // Read through a connection of its own: the writer owns f.store.
  const auto reader = RunStore::open(f.dir.path() / "run");
  EXPECT_TRUE(reader.read_samples(f.channel).empty()) << "a batch is committed whole or not at all";
  writer.flush();
  EXPECT_GE(writer.stats().failed_commits, 2) << "the batch was not kept for another try";
}

}  // namespace
}  // namespace bosfuse::storage

namespace bosfuse::storage {
namespace {

TEST(RunStore, ForEachSampleStreamsInTimeOrderAcrossChannels) {
  RunStoreFixture f;
  const auto other = f.store.add_channel({0, f.device, "tc1", "thermocouple", "degC", "K", {}, {}});
  const std::vector<Sample> samples = {{other, 30, {}, 3.0, {}, SampleStatus::kOk},
                                       {f.channel, 10, {}, 1.0, {}, SampleStatus::kOk},
                                       {other, 10, {}, 2.0, {}, SampleStatus::kOk},
                                       {f.channel, 40, {}, 4.0, {}, SampleStatus::kOk}};
  f.store.write_samples(samples);
  std::vector<double> order;
  f.store.for_each_sample([&](const Sample& s) { order.push_back(*s.value); }, {0, 35});
  EXPECT_EQ(order, (std::vector<double>{1.0, 2.0, 3.0}));
}

}  // namespace
}  // namespace bosfuse::storage
