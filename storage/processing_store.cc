#include "storage/processing_store.h"

#include <fmt/format.h>

#include <string>
#include <string_view>

#include "storage/record_rows.h"
#include "storage/run_store.h"
#include "storage/schema.h"
#include "storage/transaction.h"

namespace bosfuse::storage {
namespace {

const char* to_text(FitSubject subject) { return subject == FitSubject::kChannel ? "channel" : "probe"; }

std::vector<ProbeSeriesRecord> read_probes(Statement& stmt) {
  std::vector<ProbeSeriesRecord> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_optional_int64(1), stmt.column_text(2), stmt.column_double(3),
                   stmt.column_double(4)});
  }
  return out;
}

std::vector<ProbeSampleRecord> read_probe_samples(Statement& stmt) {
  std::vector<ProbeSampleRecord> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_int64(1), stmt.column_int64(2), stmt.column_double(3),
                   stmt.column_double(4), stmt.column_double(5), stmt.column_optional_double(6),
                   stmt.column_int64(7) != 0, stmt.column_optional_double(8), stmt.column_optional_double(9),
                   stmt.column_optional_double(10), stmt.column_optional_double(11),
                   stmt.column_optional_double(12)});
  }
  return out;
}

// The columns read_probe_samples reads, from `table`: a store opened read-only
// before version 5 has no σ columns, which read as NULL.
// The columns a result table shares with its staged twin (schema.cc builds
// both tables from one definition); a staged row is keyed by its processing
// instead of its run. A probe sample's σ come last (schema.h).
constexpr const char* kProbeSeriesColumns = "channel_id, name, x_px, y_px";
constexpr const char* kFieldColumns = "frame_id, kind, path, json";
constexpr const char* kSampleValueColumns = "probe_id, frame_id, t_ns, u_px, v_px, shift_px, temperature_c, valid";

std::string sigma_columns() {
  std::string columns;
  for (const std::string_view column : kProbeSampleSigmaColumns) {
    columns += (columns.empty() ? "" : ", ") + std::string(column);
  }
  return columns;
}

// As many NULLs as there are σ columns, for a store from before them.
std::string null_sigma_columns() {
  std::string nulls;
  for (std::size_t i = 0; i < kProbeSampleSigmaColumns.size(); ++i) nulls += i ? ", NULL" : "NULL";
  return nulls;
}

std::string sample_columns() { return std::string(kSampleValueColumns) + ", " + sigma_columns(); }

// "INSERT INTO table (columns) VALUES (?, ...)", one placeholder a column.
std::string insert_row(std::string_view table, std::string_view columns) {
  std::string marks = "?";
  for (const char c : columns) {
    if (c == ',') marks += ", ?";
  }
  return fmt::format("INSERT INTO {} ({}) VALUES ({})", table, columns, marks);
}

std::string probe_sample_select(const char* table, bool with_sigmas) {
  return std::string("SELECT ") + kSampleValueColumns + ", " +
         (with_sigmas ? sigma_columns() : null_sigma_columns()) + " FROM " + table +
         " WHERE probe_id = ? ORDER BY t_ns, frame_id";
}

void insert_probe_samples(Database& db, const char* table, std::span<const ProbeSampleRecord> samples) {
  auto stmt = db.prepare(insert_row(table, sample_columns()));
  for (const ProbeSampleRecord& s : samples) {
    stmt.bind_all(s.probe_id, s.frame_id, s.t_ns, s.u_px, s.v_px, s.shift_px, s.temperature_c, s.valid ? 1 : 0,
                  s.sigma_u_px, s.sigma_v_px, s.sigma_shift_px, s.sigma_random_c, s.sigma_systematic_c);
    stmt.run();
  }
}

std::vector<FieldRecord> read_fields(Statement& stmt) {
  std::vector<FieldRecord> out;
  while (stmt.step()) {
    out.push_back(
        {stmt.column_int64(0), stmt.column_int64(1), stmt.column_text(2), stmt.column_text(3), stmt.column_text(4)});
  }
  return out;
}

// What a processing staged, dropped (abandoned, or moved into the results).
void drop_staged(Database& db, std::int64_t processing_id) {
  for (const char* sql :
       {"DELETE FROM staged_probe_samples WHERE probe_id IN (SELECT id FROM staged_probe_series WHERE processing_id = ?1)",
        "DELETE FROM staged_probe_series WHERE processing_id = ?1",
        "DELETE FROM staged_fields WHERE processing_id = ?1", "DELETE FROM staged_frames WHERE processing_id = ?1"}) {
    db.prepare(sql).bind(1, processing_id).run();
  }
}

}  // namespace

ProcessingStore::ProcessingStore(const std::filesystem::path& run_dir, bool writable)
    : db_((RunStore::holds_run(run_dir) ? database_path(run_dir)
                                        : throw StorageError("'" + run_dir.string() + "' holds no bosfuse run")),
          writable ? Database::Mode::kReadWrite : Database::Mode::kReadOnly) {
  require_known_schema(db_);
  if (writable) migrate(db_);
  version_ = schema_version(db_);
  auto stmt = db_.prepare("SELECT id FROM runs ORDER BY id LIMIT 1");
  stmt.step();
  run_id_ = stmt.column_int64(0);
}

void ProcessingStore::in_transaction(const std::function<void()>& work) {
  Transaction transaction(db_);
  work();
  transaction.commit();
}

void ProcessingStore::clear_results() {
  for (const char* sql : {"DELETE FROM agreements WHERE run_id = ?1", "DELETE FROM fits WHERE run_id = ?1",
                          "DELETE FROM probe_samples WHERE probe_id IN (SELECT id FROM probe_series WHERE run_id = ?1)",
                          "DELETE FROM probe_series WHERE run_id = ?1", "DELETE FROM fields WHERE run_id = ?1"}) {
    db_.prepare(sql).bind(1, run_id_).run();
  }
}

std::int64_t ProcessingStore::add_probe(const ProbeSeriesRecord& p) {
  db_.prepare(insert_row("probe_series", std::string("run_id, ") + kProbeSeriesColumns))
      .bind_all(run_id_, p.channel_id, p.name, p.x_px, p.y_px)
      .run();
  return db_.last_insert_rowid();
}

void ProcessingStore::write_probe_samples(std::span<const ProbeSampleRecord> samples) {
  insert_probe_samples(db_, "probe_samples", samples);
}

std::int64_t ProcessingStore::add_fit(const FitRecord& f) {
  db_.prepare("INSERT INTO fits (run_id, subject_kind, subject_id, origin_t_ns, ok, json) VALUES (?, ?, ?, ?, ?, ?)")
      .bind_all(run_id_, to_text(f.subject), f.subject_id, f.origin_t_ns, f.ok ? 1 : 0, f.json)
      .run();
  return db_.last_insert_rowid();
}

std::int64_t ProcessingStore::add_agreement(const AgreementRecord& a) {
  db_.prepare("INSERT INTO agreements (run_id, channel_id, probe_id, json) VALUES (?, ?, ?, ?)")
      .bind_all(run_id_, a.channel_id, a.probe_id, a.json)
      .run();
  return db_.last_insert_rowid();
}

std::int64_t ProcessingStore::add_calibration(const CalibrationRecord& c) {
  db_.prepare("INSERT INTO calibrations (run_id, created_ns, json) VALUES (?, ?, ?)")
      .bind_all(run_id_, c.created_ns, c.json)
      .run();
  return db_.last_insert_rowid();
}

std::int64_t ProcessingStore::add_field(const FieldRecord& f) {
  db_.prepare(insert_row("fields", std::string("run_id, ") + kFieldColumns) +
              " ON CONFLICT (frame_id, kind) DO UPDATE SET path = excluded.path, json = excluded.json")
      .bind_all(run_id_, f.frame_id, f.kind, f.path, f.json)
      .run();
  return db_.last_insert_rowid();
}

std::int64_t ProcessingStore::begin_processing(const std::string& settings_json, std::int64_t started_ns) {
  db_.prepare("INSERT INTO processings (run_id, started_ns, status, settings_json) VALUES (?, ?, 'running', ?)")
      .bind_all(run_id_, started_ns, settings_json)
      .run();
  return db_.last_insert_rowid();
}

void ProcessingStore::update_running_settings(std::int64_t processing_id, const std::string& settings_json) {
  db_.prepare("UPDATE processings SET settings_json = ? WHERE id = ? AND status = 'running'")
      .bind_all(settings_json, processing_id)
      .run();
}

std::int64_t ProcessingStore::add_inherited_settings(const std::string& settings_json, std::int64_t created_ns) {
  db_.prepare(
         "INSERT INTO processings (run_id, started_ns, finished_ns, status, settings_json) "
         "VALUES (?1, ?2, ?2, 'inherited', ?3)")
      .bind_all(run_id_, created_ns, settings_json)
      .run();
  return db_.last_insert_rowid();
}

std::optional<ProcessingRecord> ProcessingStore::processing_where(const char* condition) const {
  if (!has_processings()) return std::nullopt;
  auto stmt = db_.prepare(std::string("SELECT id, started_ns, finished_ns, status, settings_json, summary_json "
                                      "FROM processings WHERE run_id = ? AND ") +
                          condition + " ORDER BY id DESC LIMIT 1");
  stmt.bind(1, run_id_);
  if (!stmt.step()) return std::nullopt;
  return ProcessingRecord{stmt.column_int64(0), stmt.column_int64(1), stmt.column_optional_int64(2),
                          stmt.column_text(3),  stmt.column_text(4),  stmt.column_text(5)};
}

std::optional<ProcessingRecord> ProcessingStore::current_processing() const {
  return processing_where("status = 'complete'");
}

std::optional<ProcessingRecord> ProcessingStore::latest_settings() const {
  return processing_where("status IN ('complete', 'inherited')");
}

std::optional<ProcessingRecord> ProcessingStore::unfinished_processing() const {
  return processing_where("status = 'running'");
}

std::optional<ProcessingRecord> ProcessingStore::latest_processing() const {
  return processing_where("status <> 'inherited'");
}

void ProcessingStore::fail_processing(std::int64_t processing_id, const std::string& summary_json,
                                      std::int64_t finished_ns) {
  Transaction transaction(db_);
  auto staged = db_.prepare("SELECT COUNT(*) FROM staged_frames WHERE processing_id = ?");
  staged.bind(1, processing_id).step();
  const bool resumable = staged.column_int64(0) > 0;
  if (!resumable) drop_staged(db_, processing_id);
  db_.prepare(
         "UPDATE processings SET summary_json = ?2, status = CASE WHEN ?3 THEN status ELSE 'abandoned' END, "
         "finished_ns = CASE WHEN ?3 THEN finished_ns ELSE ?4 END WHERE id = ?1 AND status = 'running'")
      .bind_all(processing_id, summary_json, resumable ? 1 : 0, finished_ns)
      .run();
  transaction.commit();
}

void ProcessingStore::abandon_processing(std::int64_t processing_id) {
  Transaction transaction(db_);
  drop_staged(db_, processing_id);
  db_.prepare("UPDATE processings SET status = 'abandoned' WHERE id = ? AND status = 'running'")
      .bind(1, processing_id)
      .run();
  transaction.commit();
}

std::int64_t ProcessingStore::stage_probe(std::int64_t processing_id, const ProbeSeriesRecord& p) {
  auto existing = db_.prepare("SELECT id FROM staged_probe_series WHERE processing_id = ? AND name = ?");
  if (existing.bind_all(processing_id, p.name).step()) return existing.column_int64(0);
  db_.prepare(insert_row("staged_probe_series", std::string("processing_id, ") + kProbeSeriesColumns))
      .bind_all(processing_id, p.channel_id, p.name, p.x_px, p.y_px)
      .run();
  return db_.last_insert_rowid();
}

std::vector<ProbeSeriesRecord> ProcessingStore::staged_probes(std::int64_t processing_id) const {
  auto stmt = db_.prepare(
      "SELECT id, channel_id, name, x_px, y_px FROM staged_probe_series WHERE processing_id = ? ORDER BY id");
  stmt.bind(1, processing_id);
  return read_probes(stmt);
}


std::vector<ProbeSampleRecord> ProcessingStore::staged_probe_samples(std::int64_t probe_id) const {
  auto stmt = db_.prepare(probe_sample_select("staged_probe_samples", has_sample_sigmas()));
  stmt.bind(1, probe_id);
  return read_probe_samples(stmt);
}

std::vector<FieldRecord> ProcessingStore::staged_fields(std::int64_t processing_id) const {
  auto stmt = db_.prepare(
      "SELECT 0, frame_id, kind, path, json FROM staged_fields WHERE processing_id = ? ORDER BY frame_id, kind");
  stmt.bind(1, processing_id);
  return read_fields(stmt);
}

void ProcessingStore::stage_frame(std::int64_t processing_id, std::int64_t frame_id, const std::string& json,
                                  std::span<const ProbeSampleRecord> samples, std::span<const FieldRecord> fields) {
  Transaction transaction(db_);
  insert_probe_samples(db_, "staged_probe_samples", samples);
  auto field = db_.prepare(insert_row("staged_fields", std::string("processing_id, ") + kFieldColumns));
  for (const FieldRecord& f : fields) {
    field.bind_all(processing_id, frame_id, f.kind, f.path, f.json);
    field.run();
  }
  db_.prepare("INSERT INTO staged_frames (processing_id, frame_id, json) VALUES (?, ?, ?)")
      .bind_all(processing_id, frame_id, json)
      .run();
  transaction.commit();
}

std::vector<std::int64_t> ProcessingStore::staged_frame_ids(std::int64_t processing_id) const {
  auto stmt = db_.prepare("SELECT frame_id FROM staged_frames WHERE processing_id = ? ORDER BY frame_id");
  stmt.bind(1, processing_id);
  std::vector<std::int64_t> out;
  while (stmt.step()) out.push_back(stmt.column_int64(0));
  return out;
}

std::vector<std::pair<std::int64_t, std::string>> ProcessingStore::staged_frame_summaries(
    std::int64_t processing_id) const {
  auto stmt = db_.prepare("SELECT frame_id, json FROM staged_frames WHERE processing_id = ? ORDER BY frame_id");
  stmt.bind(1, processing_id);
  std::vector<std::pair<std::int64_t, std::string>> out;
  while (stmt.step()) out.emplace_back(stmt.column_int64(0), stmt.column_text(1));
  return out;
}

void ProcessingStore::complete_processing(std::int64_t processing_id, std::span<const FitRecord> fits,
                                          std::span<const AgreementRecord> agreements,
                                          const std::string& summary_json, std::int64_t finished_ns) {
  Transaction transaction(db_);
  clear_results();
  // ?1 the processing, ?2 the run.
  for (const std::string& sql :
       {fmt::format("INSERT INTO probe_series (id, run_id, {0}) SELECT id, ?2, {0} FROM staged_probe_series "
                    "WHERE processing_id = ?1",
                    kProbeSeriesColumns),
        fmt::format("INSERT INTO probe_samples ({0}) SELECT {0} FROM staged_probe_samples "
                    "WHERE probe_id IN (SELECT id FROM staged_probe_series WHERE processing_id = ?1)",
                    sample_columns()),
        fmt::format("INSERT INTO fields (run_id, {0}) SELECT ?2, {0} FROM staged_fields WHERE processing_id = ?1",
                    kFieldColumns)}) {
    auto stmt = db_.prepare(sql);
    stmt.bind(1, processing_id);
    if (sql.find("?2") != std::string::npos) stmt.bind(2, run_id_);
    stmt.run();
  }
  for (const FitRecord& f : fits) add_fit(f);
  for (const AgreementRecord& a : agreements) add_agreement(a);
  drop_staged(db_, processing_id);
  db_.prepare("UPDATE processings SET status = 'complete', finished_ns = ?2, summary_json = ?3 WHERE id = ?1")
      .bind_all(processing_id, finished_ns, summary_json)
      .run();
  transaction.commit();
}

std::vector<ProbeSeriesRecord> ProcessingStore::probes() const {
  if (!has_results_tables()) return {};
  auto stmt = db_.prepare("SELECT id, channel_id, name, x_px, y_px FROM probe_series WHERE run_id = ? ORDER BY id");
  stmt.bind(1, run_id_);
  return read_probes(stmt);
}

std::vector<ProbeSampleRecord> ProcessingStore::probe_samples(std::int64_t probe_id) const {
  if (!has_results_tables()) return {};
  auto stmt = db_.prepare(probe_sample_select("probe_samples", has_sample_sigmas()));
  stmt.bind(1, probe_id);
  return read_probe_samples(stmt);
}

std::vector<FitRecord> ProcessingStore::fits() const {
  if (!has_results_tables()) return {};
  auto stmt =
      db_.prepare("SELECT id, subject_kind, subject_id, origin_t_ns, ok, json FROM fits WHERE run_id = ? ORDER BY id");
  stmt.bind(1, run_id_);
  std::vector<FitRecord> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_text(1) == "channel" ? FitSubject::kChannel : FitSubject::kProbe,
                   stmt.column_int64(2), stmt.column_int64(3), stmt.column_int64(4) != 0, stmt.column_text(5)});
  }
  return out;
}

std::vector<AgreementRecord> ProcessingStore::agreements() const {
  if (!has_results_tables()) return {};
  auto stmt = db_.prepare("SELECT id, channel_id, probe_id, json FROM agreements WHERE run_id = ? ORDER BY id");
  stmt.bind(1, run_id_);
  std::vector<AgreementRecord> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_int64(1), stmt.column_int64(2), stmt.column_text(3)});
  }
  return out;
}

std::optional<CalibrationRecord> ProcessingStore::latest_calibration() const {
  if (!has_results_tables()) return std::nullopt;
  auto stmt = db_.prepare(
      "SELECT id, created_ns, json FROM calibrations WHERE run_id = ? ORDER BY created_ns DESC, id DESC LIMIT 1");
  stmt.bind(1, run_id_);
  if (!stmt.step()) return std::nullopt;
  return CalibrationRecord{stmt.column_int64(0), stmt.column_int64(1), stmt.column_text(2)};
}

std::vector<FieldRecord> ProcessingStore::fields() const {
  if (!has_results_tables()) return {};
  auto stmt = db_.prepare("SELECT id, frame_id, kind, path, json FROM fields WHERE run_id = ? ORDER BY frame_id, kind");
  stmt.bind(1, run_id_);
  return read_fields(stmt);
}

}  // namespace bosfuse::storage
