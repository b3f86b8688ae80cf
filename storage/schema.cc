#include "storage/schema.h"

#include <fmt/format.h>

#include <array>
#include <chrono>
#include <string>
#include <tuple>
#include <type_traits>

#include "storage/experiment_clock.h"
#include "storage/records.h"
#include "storage/transaction.h"

namespace bosfuse::storage {
namespace {

constexpr std::string_view kSchemaV1 = R"sql(
CREATE TABLE runs (
  id          INTEGER PRIMARY KEY,
  name        TEXT    NOT NULL,
  started_ns  INTEGER NOT NULL,
  ended_ns    INTEGER,
  config_toml TEXT    NOT NULL,
  status      TEXT    NOT NULL CHECK (status IN ('running', 'complete', 'interrupted'))
);
CREATE TABLE devices (
  id      INTEGER PRIMARY KEY,
  run_id  INTEGER NOT NULL REFERENCES runs(id),
  name    TEXT    NOT NULL,
  kind    TEXT    NOT NULL,
  profile TEXT    NOT NULL DEFAULT '',
  address TEXT    NOT NULL DEFAULT '',
  UNIQUE (run_id, name)
);
CREATE TABLE channels (
  id         INTEGER PRIMARY KEY,
  device_id  INTEGER NOT NULL REFERENCES devices(id),
  name       TEXT    NOT NULL,
  kind       TEXT    NOT NULL,
  unit       TEXT    NOT NULL,
  tc_type    TEXT,
  image_x_px REAL,
  image_y_px REAL,
  UNIQUE (device_id, name)
);
CREATE TABLE sample_status (
  code INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE
);
INSERT INTO sample_status (code, name) VALUES
  (0, 'ok'), (1, 'open-circuit'), (2, 'out-of-range'), (3, 'timeout'),
  (4, 'bad-reply'), (5, 'invalid-value'), (6, 'disabled');
CREATE TABLE samples (
  channel_id  INTEGER NOT NULL REFERENCES channels(id),
  t_ns        INTEGER NOT NULL,
  device_t_ns INTEGER,
  value       REAL,
  raw         REAL,
  status      INTEGER NOT NULL REFERENCES sample_status(code),
  CHECK ((status = 0) = (value IS NOT NULL))
);
CREATE INDEX samples_by_channel_time ON samples (channel_id, t_ns);
CREATE TABLE frames (
  id           INTEGER PRIMARY KEY,
  device_id    INTEGER REFERENCES devices(id),
  t_ns         INTEGER NOT NULL,
  device_t_ns  INTEGER,
  path         TEXT    NOT NULL UNIQUE,
  width_px     INTEGER NOT NULL,
  height_px    INTEGER NOT NULL,
  bit_depth    INTEGER NOT NULL,
  is_reference INTEGER NOT NULL DEFAULT 0 CHECK (is_reference IN (0, 1))
);
CREATE INDEX frames_by_time ON frames (t_ns);
CREATE TABLE events (
  id        INTEGER PRIMARY KEY,
  run_id    INTEGER NOT NULL REFERENCES runs(id),
  device_id INTEGER REFERENCES devices(id),
  t_ns      INTEGER NOT NULL,
  kind      TEXT    NOT NULL,
  message   TEXT    NOT NULL
);
CREATE INDEX events_by_time ON events (t_ns);
)sql";

// The result tables and their staged twins (version 4) share their columns:
// a staged row is a result row keyed by its processing instead of its run.
// Each shared block is written once here and both tables are built from it.
constexpr std::string_view kProbeSeriesColumns = R"sql(
  channel_id INTEGER REFERENCES channels(id),
  name       TEXT    NOT NULL,
  x_px       REAL    NOT NULL,
  y_px       REAL    NOT NULL,)sql";
constexpr std::string_view kProbeSampleColumns = R"sql(
  frame_id      INTEGER NOT NULL REFERENCES frames(id),
  t_ns          INTEGER NOT NULL,
  u_px          REAL    NOT NULL,
  v_px          REAL    NOT NULL,
  shift_px      REAL    NOT NULL,
  temperature_c REAL,
  valid         INTEGER NOT NULL CHECK (valid IN (0, 1)),
  PRIMARY KEY (probe_id, frame_id)
);)sql";
constexpr std::string_view kFieldColumns = R"sql(
  frame_id INTEGER NOT NULL REFERENCES frames(id),
  kind     TEXT    NOT NULL CHECK (kind IN ('displacement', 'temperature')),
  path     TEXT    NOT NULL,
  json     TEXT    NOT NULL,)sql";

// What keys a row: its run (a result) or its processing (a staged row).
struct Owner {
  std::string_view column;  // the key column's definition
  std::string_view key;     // its name
};
constexpr Owner kRunOwner{"run_id INTEGER NOT NULL REFERENCES runs(id)", "run_id"};
constexpr Owner kProcessingOwner{"processing_id INTEGER NOT NULL REFERENCES processings(id)", "processing_id"};

std::string probe_series_table(std::string_view table, const Owner& owner) {
  return fmt::format("CREATE TABLE {} (\n  id INTEGER PRIMARY KEY,\n  {},{}\n  UNIQUE ({}, name)\n);\n", table,
                     owner.column, kProbeSeriesColumns, owner.key);
}

std::string probe_samples_table(std::string_view table, std::string_view series) {
  return fmt::format("CREATE TABLE {} (\n  probe_id INTEGER NOT NULL REFERENCES {}(id) ON DELETE CASCADE,{}\n", table,
                     series, kProbeSampleColumns);
}

// A stored field has an id of its own and one row per frame and kind; a
// staged one is keyed by its processing, frame and kind.
std::string fields_table(std::string_view table, std::string_view leading_columns, std::string_view key) {
  return fmt::format("CREATE TABLE {} ({}{}\n  {}\n);\n", table, leading_columns, kFieldColumns, key);
}

// Version 2: results of `bosfuse process` and `bosfuse calibrate`. Numbers,
// JSON text and paths only; fields themselves are files under RUN/fields/.
std::string schema_v2() {
  return probe_series_table("probe_series", kRunOwner) + probe_samples_table("probe_samples", "probe_series") +
         R"sql(CREATE TABLE fits (
  id           INTEGER PRIMARY KEY,
  run_id       INTEGER NOT NULL REFERENCES runs(id),
  subject_kind TEXT    NOT NULL CHECK (subject_kind IN ('channel', 'probe')),
  subject_id   INTEGER NOT NULL,
  origin_t_ns  INTEGER NOT NULL,
  ok           INTEGER NOT NULL CHECK (ok IN (0, 1)),
  json         TEXT    NOT NULL
);
CREATE TABLE agreements (
  id         INTEGER PRIMARY KEY,
  run_id     INTEGER NOT NULL REFERENCES runs(id),
  channel_id INTEGER NOT NULL REFERENCES channels(id),
  probe_id   INTEGER NOT NULL REFERENCES probe_series(id) ON DELETE CASCADE,
  json       TEXT    NOT NULL
);
CREATE TABLE calibrations (
  id         INTEGER PRIMARY KEY,
  run_id     INTEGER NOT NULL REFERENCES runs(id),
  created_ns INTEGER NOT NULL,
  json       TEXT    NOT NULL
);
)sql" + fields_table("fields", fmt::format("\n  id INTEGER PRIMARY KEY,\n  {},", kRunOwner.column),
                      "UNIQUE (frame_id, kind)");
}

// Version 3: what a run whose logger died needs to say what is missing: the
// logger's last sign of life (a heartbeat with every commit) and, when the
// run was started for a set duration, when it was meant to end.
constexpr std::string_view kSchemaV3 = R"sql(
ALTER TABLE runs ADD COLUMN alive_ns INTEGER;
ALTER TABLE runs ADD COLUMN planned_end_ns INTEGER;
)sql";

// Version 4: a run is a self-describing record. Its time scale and declared
// origin make every command read it in experiment seconds; each `process`
// is a row of `processings` holding the settings it used, and its results
// are written aside (staged_*) while it runs, so an interrupted process
// never mixes with the results it is replacing and can be resumed. On
// success the staged rows replace the current results in one transaction.
std::string schema_v4() {
  return R"sql(
ALTER TABLE runs ADD COLUMN time_scale REAL NOT NULL DEFAULT 1 CHECK (time_scale > 0);
ALTER TABLE runs ADD COLUMN origin_event TEXT;
CREATE TABLE processings (
  id            INTEGER PRIMARY KEY,
  run_id        INTEGER NOT NULL REFERENCES runs(id),
  started_ns    INTEGER NOT NULL,
  finished_ns   INTEGER,
  status        TEXT    NOT NULL CHECK (status IN ('running', 'complete', 'abandoned', 'inherited')),
  settings_json TEXT    NOT NULL,
  summary_json  TEXT    NOT NULL DEFAULT '{}'
);
CREATE TABLE staged_frames (
  processing_id INTEGER NOT NULL REFERENCES processings(id),
  frame_id      INTEGER NOT NULL REFERENCES frames(id),
  json          TEXT    NOT NULL,
  PRIMARY KEY (processing_id, frame_id)
);
)sql" + probe_series_table("staged_probe_series", kProcessingOwner) +
         probe_samples_table("staged_probe_samples", "staged_probe_series") +
         fields_table("staged_fields", fmt::format("\n  {},", kProcessingOwner.column),
                      "PRIMARY KEY (processing_id, frame_id, kind)");
}

// Version 5: each probe sample carries its uncertainty, NULL where it was
// not estimated (an older run's samples, a field without σ): the σ of the
// probe's shift components and of its magnitude (px), and the random and the
// systematic (Type-B) standard uncertainty of its temperature (°C); in the
// results and in the staged samples alike.
std::string schema_v5() {
  std::string sql;
  for (const char* table : {"probe_samples", "staged_probe_samples"}) {
    for (const std::string_view column : kProbeSampleSigmaColumns) {
      sql += fmt::format("ALTER TABLE {} ADD COLUMN {} REAL;\n", table, column);
    }
  }
  return sql;
}

// Version 6: what a reading and a frame need to be shown faithfully. A
// channel's resolution (its unit's smallest step, NULL where the device does
// not say) sets the digits its values are printed with; a frame's arrival
// time on the host is kept beside the time it is filed at, which for a
// camera with its own clock is the camera's time mapped to the host clock.
constexpr std::string_view kSchemaV6 = R"sql(
ALTER TABLE channels ADD COLUMN resolution REAL CHECK (resolution IS NULL OR resolution > 0);
ALTER TABLE frames ADD COLUMN arrival_ns INTEGER;
)sql";

// Version 7: a channel's samples are read from their index alone. The index
// by (channel, time) also holds each sample's value and status, which is all
// a channel's series needs, so reading one (RunStore::read_sample_columns,
// the Python Run.samples) skips the table lookup per row: about a quarter
// of the read for +23 % in file size (docs/BENCHMARKS.md, "From Python").
// Samples of one channel at the same instant come in the index's order
// (value, status, then insertion) for every reader alike.
constexpr std::string_view kSchemaV7 = R"sql(
DROP INDEX samples_by_channel_time;
CREATE INDEX samples_by_channel_time_value ON samples (channel_id, t_ns, value, status);
)sql";

static_assert(kSampleStatusCount == 7, "update the sample_status rows of the schema");

bool has_version_table(Database& db) {
  auto stmt = db.prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'schema_version'");
  return stmt.step();
}

}  // namespace

std::span<const Migration> schema_migrations() {
  // Built once: Migration holds views of these strings.
  static const std::array<std::string, 3> derived = {schema_v2(), schema_v4(), schema_v5()};
  static const std::array<Migration, 7> migrations = {{{1, kSchemaV1},
                                                       {2, derived[0]},
                                                       {3, kSchemaV3},
                                                       {4, derived[1]},
                                                       {5, derived[2]},
                                                       {6, kSchemaV6},
                                                       {7, kSchemaV7}}};
  static_assert(std::tuple_size_v<std::remove_reference_t<decltype(migrations)>> == kSchemaVersion);
  return migrations;
}

int schema_version(Database& db) {
  if (!has_version_table(db)) return 0;
  auto stmt = db.prepare("SELECT COALESCE(MAX(version), 0) FROM schema_version");
  stmt.step();
  return static_cast<int>(stmt.column_int64(0));
}

void require_known_schema(Database& db, int newest) {
  const int version = schema_version(db);
  if (version > newest) {
    throw StorageError("run store '" + db.path() + "' has schema version " + std::to_string(version) +
                       ", newer than this bosfuse understands (" + std::to_string(newest) +
                       "); read it with the bosfuse that wrote it");
  }
}

int migrate(Database& db, std::span<const Migration> migrations) {
  require_known_schema(db, migrations.empty() ? 0 : migrations.back().version);
  const int start = schema_version(db);
  for (const Migration& migration : migrations) {
    if (migration.version <= start) continue;
    Transaction transaction(db);
    db.execute("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER PRIMARY KEY, applied_ns INTEGER NOT NULL)");
    db.execute(migration.sql);
    db.prepare("INSERT INTO schema_version (version, applied_ns) VALUES (?, ?)")
        .bind(1, migration.version)
        .bind(2, utc_now_ns())
        .run();
    transaction.commit();
  }
  return start;
}

}  // namespace bosfuse::storage
