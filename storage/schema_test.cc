#include "storage/schema.h"

#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <vector>

#include "storage/records.h"
#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

std::vector<std::string> table_names(Database& db) {
  auto stmt = db.prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name");
  std::vector<std::string> names;
  while (stmt.step()) names.push_back(stmt.column_text(0));
  return names;
}

TEST(Schema, EmptyFileIsMigratedToTheCurrentVersion) {
  testing::TempDir dir;
  const auto path = (dir / "empty.sqlite").string();
  std::ofstream(path).close();  // a zero-byte file, as left by a crashed create
  Database db(path, Database::Mode::kReadWrite);
  EXPECT_EQ(schema_version(db), 0);
  EXPECT_EQ(migrate(db), 0);
  EXPECT_EQ(schema_version(db), kSchemaVersion);
  EXPECT_EQ(table_names(db), (std::vector<std::string>{"agreements", "calibrations", "channels", "devices", "events",
                                                       "fields", "fits", "frames", "probe_samples", "probe_series",
                                                       "processings", "runs", "sample_status", "samples",
                                                       "schema_version", "staged_fields", "staged_frames",
                                                       "staged_probe_samples", "staged_probe_series"}));
}

TEST(Schema, MigratingTwiceChangesNothing) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  EXPECT_EQ(migrate(db), kSchemaVersion);
  auto stmt = db.prepare("SELECT COUNT(*) FROM schema_version");
  stmt.step();
  EXPECT_EQ(stmt.column_int64(0), kSchemaVersion);
}

TEST(Schema, SampleStatusNamesMatchTheEnum) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  auto stmt = db.prepare("SELECT code, name FROM sample_status ORDER BY code");
  int count = 0;
  while (stmt.step()) {
    EXPECT_EQ(stmt.column_text(1), to_string(static_cast<SampleStatus>(stmt.column_int64(0))));
    ++count;
  }
  EXPECT_EQ(count, kSampleStatusCount);
}

TEST(Schema, ForwardMigrationAppliesOnlyNewerSteps) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  std::vector<Migration> future(schema_migrations().begin(), schema_migrations().end());
  future.push_back({kSchemaVersion + 1, "ALTER TABLE runs ADD COLUMN operator TEXT NOT NULL DEFAULT ''"});
  EXPECT_EQ(migrate(db, future), kSchemaVersion);
  EXPECT_EQ(schema_version(db), kSchemaVersion + 1);
  EXPECT_NO_THROW(db.execute("SELECT operator FROM runs"));
}

TEST(Schema, NewerStoreIsRefused) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  db.execute("INSERT INTO schema_version (version, applied_ns) VALUES (99, 0)");
  try {
    migrate(db);
    FAIL() << "a store from a newer bosfuse was accepted";
  } catch (const StorageError& e) {
    EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
  }
}

TEST(Schema, FailedMigrationLeavesTheStoreAsItWas) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  std::vector<Migration> broken(schema_migrations().begin(), schema_migrations().end());
  broken.push_back({kSchemaVersion + 1, "CREATE TABLE extra (x); THIS IS NOT SQL"});
  EXPECT_THROW(migrate(db, broken), StorageError);
  EXPECT_EQ(schema_version(db), kSchemaVersion);
  auto stmt = db.prepare("SELECT 1 FROM sqlite_master WHERE name = 'extra'");
  EXPECT_FALSE(stmt.step()) << "a failed migration left a table behind";
}

TEST(Schema, VersionOneStoreIsMigratedToTheNewestKeepingItsData) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db, schema_migrations().first(1));
  db.execute("INSERT INTO runs (name, started_ns, config_toml, status) VALUES ('old', 5, '', 'complete')");
  ASSERT_EQ(schema_version(db), 1);
  EXPECT_EQ(migrate(db), 1);
  EXPECT_EQ(schema_version(db), kSchemaVersion);
  auto stmt = db.prepare("SELECT name FROM runs");
  ASSERT_TRUE(stmt.step());
  EXPECT_EQ(stmt.column_text(0), "old");
  EXPECT_NO_THROW(db.execute("SELECT probe_id, frame_id, shift_px, temperature_c FROM probe_samples"));
}

std::string query_plan(Database& db, const std::string& sql) {
  auto stmt = db.prepare("EXPLAIN QUERY PLAN " + sql);
  std::string plan;
  while (stmt.step()) plan += stmt.column_text(3) + "\n";
  return plan;
}

// Version 7: a channel's time, value and status come from the index alone,
// in time order without a sort; a version 6 store's samples survive the
// index's rebuild.
TEST(Schema, AChannelsSeriesIsReadFromItsIndexAloneSinceVersionSeven) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db, schema_migrations().first(6));
  db.execute("INSERT INTO runs (name, started_ns, config_toml, status) VALUES ('old', 5, '', 'complete')");
  db.execute("INSERT INTO devices (run_id, name, kind) VALUES (1, 'adam', 'modbus-tcp')");
  db.execute("INSERT INTO channels (device_id, name, kind, unit) VALUES (1, 'tc0', 'thermocouple', 'degC')");
  db.execute("INSERT INTO samples (channel_id, t_ns, value, status) VALUES (1, 20, 21.5, 0), (1, 10, NULL, 3)");
  const std::string series = "SELECT t_ns, value, status FROM samples WHERE channel_id = 1 ORDER BY t_ns";
  EXPECT_EQ(query_plan(db, series).find("COVERING INDEX"), std::string::npos) << "version 6 already covered it";

  migrate(db);
  const std::string plan = query_plan(db, series);
  EXPECT_NE(plan.find("COVERING INDEX samples_by_channel_time_value"), std::string::npos) << plan;
  EXPECT_EQ(plan.find("TEMP B-TREE"), std::string::npos) << "the series is sorted after reading: " << plan;
  auto rows = db.prepare(series);
  std::vector<std::int64_t> times;
  while (rows.step()) times.push_back(rows.column_int64(0));
  EXPECT_EQ(times, (std::vector<std::int64_t>{10, 20}));
}

TEST(Schema, ProcessingTablesRejectWhatTheyDoNotMean) {
  testing::TempDir dir;
  Database db((dir / "run.sqlite").string(), Database::Mode::kCreate);
  migrate(db);
  db.execute("INSERT INTO runs (name, started_ns, config_toml, status) VALUES ('r', 5, '', 'complete')");
  EXPECT_THROW(db.execute("INSERT INTO fits (run_id, subject_kind, subject_id, origin_t_ns, ok, json) "
                          "VALUES (1, 'camera', 1, 0, 1, '{}')"),
               StorageError);
  EXPECT_THROW(db.execute("INSERT INTO fields (run_id, frame_id, kind, path, json) VALUES (1, 99, 'displacement', "
                          "'f.csv', '{}')"),
               StorageError)
      << "a field of a frame that does not exist";
}

}  // namespace
}  // namespace bosfuse::storage
