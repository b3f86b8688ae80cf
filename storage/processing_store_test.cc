#include "storage/processing_store.h"

#include <gtest/gtest.h>

#include <array>
#include <string>

#include "storage/run_store.h"
#include "storage/schema.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

struct ProcessingStoreFixture {
  testing::TempDir dir;
  std::filesystem::path run_dir = dir.path() / "run";
  RunStore store = RunStore::create(run_dir, {0, "r", 1'000, std::nullopt, "", RunStatus::kRunning, 1.0, std::nullopt},
                                    RunStore::CreateMode::kNew);
  std::int64_t device = store.add_device({0, "adam", "modbus-tcp", "adam-6018", "127.0.0.1:502"});
  std::int64_t channel = store.add_channel({0, device, "tc0", "thermocouple", "degC", "K", 120.5, 80.0});
  std::int64_t reference = store.add_frame({0, std::nullopt, 1'000, std::nullopt, "frames/0.png", 64, 48, 8, true});
  std::int64_t frame = store.add_frame({0, std::nullopt, 2'000, std::nullopt, "frames/1.png", 64, 48, 8, false});
};

TEST(ProcessingStore, WritesAndReadsEveryKindOfResult) {
  ProcessingStoreFixture f;
  ProcessingStore results(f.run_dir, true);
  std::int64_t probe = 0;
  results.in_transaction([&] {
    probe = results.add_probe({0, f.channel, "tc0", 120.5, 80.0});
    const std::vector<ProbeSampleRecord> samples{
        {probe, f.frame, 2'000, 0.3, -0.4, 0.5, 31.5, true, {}, {}, {}, {}, {}},
        {probe, f.reference, 1'000, 0, 0, 0, std::nullopt, false, {}, {}, {}, {}, {}}};
    results.write_probe_samples(samples);
    results.add_fit({0, FitSubject::kProbe, probe, 1'000, true, R"({"k_per_s":0.01})"});
    results.add_fit({0, FitSubject::kChannel, f.channel, 1'000, false, "{}"});
    results.add_agreement({0, f.channel, probe, R"({"verdict":"agree"})"});
    results.add_field({0, f.frame, "displacement", "fields/1_displacement.csv", "{}"});
  });
  results.add_calibration({0, 5, R"({"slope":20})"});
  results.add_calibration({0, 9, R"({"slope":25})"});

  ProcessingStore reader(f.run_dir);
  ASSERT_EQ(reader.probes().size(), 1u);
  EXPECT_EQ(reader.probes()[0].channel_id, f.channel);
  const auto samples = reader.probe_samples(probe);
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_EQ(samples[0].frame_id, f.reference) << "in time order";
  EXPECT_FALSE(samples[0].temperature_c.has_value());
  EXPECT_DOUBLE_EQ(*samples[1].temperature_c, 31.5);
  EXPECT_TRUE(samples[1].valid);
  ASSERT_EQ(reader.fits().size(), 2u);
  EXPECT_EQ(reader.fits()[0].subject, FitSubject::kProbe);
  EXPECT_FALSE(reader.fits()[1].ok);
  EXPECT_EQ(reader.agreements().at(0).json, R"({"verdict":"agree"})");
  EXPECT_EQ(reader.fields().at(0).path, "fields/1_displacement.csv");
  EXPECT_EQ(reader.latest_calibration()->json, R"({"slope":25})");
}

TEST(ProcessingStore, ClearingKeepsCalibrationsAndAFailedTransactionStoresNothing) {
  ProcessingStoreFixture f;
  ProcessingStore results(f.run_dir, true);
  const auto probe = results.add_probe({0, std::nullopt, "p", 1, 2});
  const std::vector<ProbeSampleRecord> samples{
      {probe, f.frame, 2'000, 0, 0, 0, std::nullopt, true, {}, {}, {}, {}, {}}};
  results.write_probe_samples(samples);
  results.add_calibration({0, 5, "{}"});
  results.clear_results();
  EXPECT_TRUE(results.probes().empty());
  EXPECT_TRUE(results.probe_samples(probe).empty());
  EXPECT_TRUE(results.latest_calibration().has_value());
  EXPECT_THROW(results.in_transaction([&] {
    results.add_probe({0, std::nullopt, "q", 1, 2});
    throw std::runtime_error("interrupted");
  }),
               std::runtime_error);
  EXPECT_TRUE(results.probes().empty());
}

// A processing that failed before any frame leaves no `running` row and
// nothing staged; one that failed after a frame stays resumable. Both keep
// the error in their summary.
TEST(ProcessingStore, AFailedProcessingIsAbandonedUnlessAFrameWasStagedAndKeepsItsError) {
  ProcessingStoreFixture f;
  ProcessingStore results(f.run_dir, true);
  const std::int64_t early = results.begin_processing("{}", 10);
  const std::int64_t probe = results.stage_probe(early, {0, f.channel, "tc0", 120.5, 80.0});
  results.fail_processing(early, R"({"failure":"no reference frame"})", 20);
  EXPECT_FALSE(results.unfinished_processing().has_value()) << "no running row stays";
  const auto last = results.latest_processing();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->id, early);
  EXPECT_EQ(last->status, "abandoned");
  EXPECT_EQ(last->finished_ns, 20);
  EXPECT_EQ(last->summary_json, R"({"failure":"no reference frame"})");
  EXPECT_TRUE(results.staged_probes(early).empty());
  EXPECT_TRUE(results.staged_probe_samples(probe).empty());

  const std::int64_t later = results.begin_processing("{}", 30);
  results.stage_frame(later, f.frame, "{}", {}, {});
  results.fail_processing(later, R"({"failure":"frame 3: unreadable"})", 40);
  const auto unfinished = results.unfinished_processing();
  ASSERT_TRUE(unfinished.has_value()) << "a staged frame: resumable";
  EXPECT_EQ(unfinished->id, later);
  EXPECT_FALSE(unfinished->finished_ns.has_value());
  EXPECT_EQ(unfinished->summary_json, R"({"failure":"frame 3: unreadable"})");
  EXPECT_EQ(results.staged_frame_ids(later), std::vector<std::int64_t>{f.frame});
  EXPECT_EQ(results.latest_processing()->id, later);
  results.add_inherited_settings("{}", 50);
  EXPECT_EQ(results.latest_processing()->id, later) << "inherited settings are no processing";
}

// Takes a store back to version 6 by restoring the index version 7 replaced.
void drop_schema_v7(Database& db) {
  db.execute("DROP INDEX samples_by_channel_time_value");
  db.execute("CREATE INDEX samples_by_channel_time ON samples (channel_id, t_ns)");
  db.execute("DELETE FROM schema_version WHERE version >= 7");
}

// Takes a store back to version 5 by removing what versions 6 and 7 added.
void drop_schema_v6(Database& db) {
  drop_schema_v7(db);
  db.execute("ALTER TABLE channels DROP COLUMN resolution");
  db.execute("ALTER TABLE frames DROP COLUMN arrival_ns");
  db.execute("DELETE FROM schema_version WHERE version >= 6");
}

TEST(ProcessingStore, AVersionOneStoreReadsAsEmptyAndIsMigratedWhenWritten) {
  ProcessingStoreFixture f;
  {
    Database db((f.run_dir / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
    drop_schema_v6(db);
    for (const char* table :
         {"staged_probe_samples", "staged_probe_series", "staged_fields", "staged_frames", "processings",
          "probe_samples", "agreements", "fits", "probe_series", "calibrations", "fields"}) {
      db.execute(std::string("DROP TABLE ") + table);
    }
    db.execute("ALTER TABLE runs DROP COLUMN time_scale");
    db.execute("ALTER TABLE runs DROP COLUMN origin_event");
    db.execute("ALTER TABLE runs DROP COLUMN alive_ns");
    db.execute("ALTER TABLE runs DROP COLUMN planned_end_ns");
    db.execute("DELETE FROM schema_version WHERE version >= 2");
  }
  EXPECT_TRUE(ProcessingStore(f.run_dir).probes().empty());
  EXPECT_FALSE(ProcessingStore(f.run_dir).latest_calibration().has_value());
  EXPECT_FALSE(ProcessingStore(f.run_dir).current_processing().has_value());
  EXPECT_DOUBLE_EQ(RunStore::open(f.run_dir).run().time_scale, 1.0) << "an old store read-only: recorded in real time";
  ProcessingStore writer(f.run_dir, true);
  EXPECT_NO_THROW(writer.add_probe({0, std::nullopt, "p", 1, 2}));
  EXPECT_THROW(ProcessingStore(f.dir.path() / "nothing"), StorageError);
}

constexpr std::array<const char*, 5> kSigmaColumns = {"sigma_u_px", "sigma_v_px", "sigma_shift_px", "sigma_random_c",
                                                      "sigma_systematic_c"};

TEST(ProcessingStore, SampleUncertaintiesRoundTripThroughTheStagedCopy) {
  ProcessingStoreFixture f;
  ProcessingStore results(f.run_dir, true);
  const auto processing = results.begin_processing("{}", 1'000);
  const auto probe = results.stage_probe(processing, {0, f.channel, "tc0", 120.5, 80.0});
  ProbeSampleRecord with{probe, f.frame, 2'000, 0.3, -0.4, 0.5, 31.5, true, 0.01, 0.02, 0.018, 0.4, 2.6};
  ProbeSampleRecord without{probe, f.reference, 1'000, 0, 0, 0, std::nullopt, false, {}, {}, {}, {}, {}};
  const std::vector<ProbeSampleRecord> samples{with, without};
  results.stage_frame(processing, f.frame, "{}", samples, {});
  const auto staged = results.staged_probe_samples(probe);
  ASSERT_EQ(staged.size(), 2u);
  EXPECT_DOUBLE_EQ(*staged[1].sigma_systematic_c, 2.6);
  results.complete_processing(processing, {}, {}, "{}", 3'000);
  const auto stored = ProcessingStore(f.run_dir).probe_samples(probe);
  ASSERT_EQ(stored.size(), 2u);
  EXPECT_FALSE(stored[0].sigma_u_px || stored[0].sigma_v_px || stored[0].sigma_shift_px || stored[0].sigma_random_c ||
               stored[0].sigma_systematic_c)
      << "not estimated reads as NULL, not 0";
  EXPECT_DOUBLE_EQ(*stored[1].sigma_u_px, 0.01);
  EXPECT_DOUBLE_EQ(*stored[1].sigma_v_px, 0.02);
  EXPECT_DOUBLE_EQ(*stored[1].sigma_shift_px, 0.018);
  EXPECT_DOUBLE_EQ(*stored[1].sigma_random_c, 0.4);
  EXPECT_DOUBLE_EQ(*stored[1].sigma_systematic_c, 2.6);
}

TEST(ProcessingStore, EachStagedFrameKeepsItsSummaryUntilTheProcessingCompletes) {
  ProcessingStoreFixture f;
  ProcessingStore results(f.run_dir, true);
  const auto processing = results.begin_processing("{}", 1'000);
  results.stage_frame(processing, f.frame, R"({"refused":{"reason":"not the same scene"}})", {}, {});
  const auto summaries = results.staged_frame_summaries(processing);
  ASSERT_EQ(summaries.size(), 1u);
  EXPECT_EQ(summaries[0].first, f.frame);
  EXPECT_EQ(summaries[0].second, R"({"refused":{"reason":"not the same scene"}})");
  EXPECT_TRUE(results.staged_frame_summaries(processing + 1).empty()) << "another processing's frames are not these";
}

// A run processed by a bosfuse of schema version 4: its samples have no σ
// columns. Read-only it reads with every σ absent; opened for writing it is
// migrated, the old samples' σ NULL, and new samples carry theirs.
TEST(ProcessingStore, AVersionFourRunReadsWithoutSigmasAndMigratesWhenWritten) {
  ProcessingStoreFixture f;
  std::int64_t probe = 0;
  {
    ProcessingStore results(f.run_dir, true);
    probe = results.add_probe({0, f.channel, "tc0", 120.5, 80.0});
  }
  {
    Database db((f.run_dir / RunStore::kDatabaseFileName).string(), Database::Mode::kReadWrite);
    drop_schema_v6(db);
    for (const char* table : {"probe_samples", "staged_probe_samples"}) {
      for (const char* column : kSigmaColumns) {
        db.execute(std::string("ALTER TABLE ") + table + " DROP COLUMN " + column);
      }
    }
    db.execute("DELETE FROM schema_version WHERE version >= 5");
    db.prepare(
          "INSERT INTO probe_samples (probe_id, frame_id, t_ns, u_px, v_px, shift_px, temperature_c, valid) "
          "VALUES (?, ?, 2000, 0.3, -0.4, 0.5, 31.5, 1)")
        .bind_all(probe, f.frame)
        .run();
    ASSERT_EQ(schema_version(db), 4);
  }
  const auto old = ProcessingStore(f.run_dir).probe_samples(probe);
  ASSERT_EQ(old.size(), 1u);
  EXPECT_DOUBLE_EQ(*old[0].temperature_c, 31.5);
  EXPECT_FALSE(old[0].sigma_shift_px.has_value());
  EXPECT_FALSE(old[0].sigma_random_c.has_value());
  {
    Database db((f.run_dir / RunStore::kDatabaseFileName).string(), Database::Mode::kReadOnly);
    EXPECT_EQ(schema_version(db), 4) << "reading changed nothing";
  }
  ProcessingStore writer(f.run_dir, true);
  const std::vector<ProbeSampleRecord> added{
      {probe, f.reference, 1'000, 0, 0, 0, 20.0, true, 0.01, 0.01, 0.01, 0.2, 0.5}};
  writer.write_probe_samples(added);
  const auto both = writer.probe_samples(probe);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_DOUBLE_EQ(*both[0].sigma_random_c, 0.2);
  EXPECT_FALSE(both[1].sigma_random_c.has_value()) << "the migrated sample's σ is NULL";
  EXPECT_DOUBLE_EQ(*both[1].temperature_c, 31.5);
}

}  // namespace
}  // namespace bosfuse::storage
