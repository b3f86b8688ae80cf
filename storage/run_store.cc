#include "storage/run_store.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <system_error>

#include "storage/record_rows.h"
#include "storage/schema.h"
#include "storage/space_reserve.h"
#include "storage/transaction.h"

namespace bosfuse::storage {
namespace {

namespace fs = std::filesystem;

RunInfo read_run(Statement& stmt) {
  RunInfo run;
  run.id = stmt.column_int64(0);
  run.name = stmt.column_text(1);
  run.started_ns = stmt.column_int64(2);
  run.ended_ns = stmt.column_optional_int64(3);
  run.config_toml = stmt.column_text(4);
  run.status = run_status_from_string(stmt.column_text(5));
  run.time_scale = stmt.column_double(6);
  run.origin_event = stmt.column_optional_text(7);
  return run;
}

void bind_range(Statement& stmt, int first_index, TimeRange range) {
  stmt.bind(first_index, range.from_ns).bind(first_index + 1, range.to_ns);
}

std::string seconds_text(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f s", static_cast<double>(ns) * 1e-9);
  return text;
}

// "line 7: `host = \"a\"` became `host = \"b\"`", naming the first line that differs.
std::string first_difference(const std::string& before, const std::string& after) {
  std::istringstream a(before), b(after);
  std::string line_a, line_b;
  for (int line = 1;; ++line) {
    const bool more_a = static_cast<bool>(std::getline(a, line_a));
    const bool more_b = static_cast<bool>(std::getline(b, line_b));
    if (!more_a && !more_b) return "they differ only in line endings";
    if (!more_a) line_a = "(end of file)";
    if (!more_b) line_b = "(end of file)";
    if (line_a != line_b) return "line " + std::to_string(line) + ": `" + line_a + "` became `" + line_b + "`";
  }
}

// Before anything may write to the run (taking its lock, closing a run
// whose logger died), so that a refused store is left exactly as it was.
void refuse_newer_schema(const fs::path& run_dir) {
  Database db(database_path(run_dir), Database::Mode::kReadOnly);
  require_known_schema(db);
}

RunStatus stored_status(const fs::path& run_dir) {
  Database db(database_path(run_dir), Database::Mode::kReadOnly);
  auto stmt = db.prepare("SELECT status FROM runs ORDER BY id LIMIT 1");
  return stmt.step() ? run_status_from_string(stmt.column_text(0)) : RunStatus::kComplete;
}

}  // namespace

RunStore::RunStore(fs::path dir, Database::Mode mode) : dir_(std::move(dir)), db_(database_path(dir_), mode) {
  require_known_schema(db_);
}

bool RunStore::holds_run(const fs::path& run_dir) {
  std::error_code ec;
  if (!fs::exists(run_dir / kDatabaseFileName, ec)) return false;
  Database db(database_path(run_dir), Database::Mode::kReadOnly);
  if (schema_version(db) == 0) return false;
  auto stmt = db.prepare("SELECT 1 FROM runs LIMIT 1");
  return stmt.step();
}

RunStore RunStore::create(const fs::path& run_dir, const RunInfo& info, CreateMode mode) {
  const bool existing = holds_run(run_dir);
  if (existing && mode == CreateMode::kNew) {
    throw StorageError("'" + run_dir.string() + "' already holds a run; choose another folder, or append to it (acquire --append)");
  }
  if (existing) refuse_newer_schema(run_dir);
  fs::create_directories(run_dir);
  std::optional<RunLock> lock = RunLock::try_acquire(run_dir);
  if (!lock) {
    throw StorageError("'" + run_dir.string() + "' is being recorded by another logger (" +
                       RunLock::holder(run_dir) + ")");
  }
  RunStore store(run_dir, Database::Mode::kCreate);
  migrate(store.db_);
  if (existing) {
    store.resume(store.run(), info);
  } else {
    store.run_id_ = store.insert_run(info);
  }
  store.lock_ = std::move(lock);
  return store;
}

// Appending continues one experiment: the same experiment file, and a run
// left open by a dead logger is closed as interrupted before it goes on.
void RunStore::resume(const RunInfo& previous, const RunInfo& info) {
  run_id_ = previous.id;
  if (!previous.config_toml.empty() && previous.config_toml != info.config_toml) {
    throw StorageError("'" + dir_.string() + "' was recorded with a different experiment file (" +
                       first_difference(previous.config_toml, info.config_toml) +
                       "); log into a new folder, or append with the experiment file the run was started with");
  }
  if (previous.status == RunStatus::kRunning) close_interrupted();
  const RunStatus before = run().status;
  db_.prepare("UPDATE runs SET status = 'running', ended_ns = NULL, planned_end_ns = NULL WHERE id = ?")
      .bind(1, run_id_)
      .run();
  const Event appended{0, std::nullopt, info.started_ns, "appended",
                       "logging resumed in this run; the previous session ended " + std::string(to_string(before))};
  write_events({&appended, 1});
}

// The account of a run whose logger died: where the record ends, the last
// sign of life, and what was planned but never recorded.
void RunStore::close_interrupted() {
  auto stmt = db_.prepare("SELECT started_ns, alive_ns, planned_end_ns FROM runs WHERE id = ?");
  stmt.bind(1, run_id_).step();
  const std::int64_t started_ns = stmt.column_int64(0);
  const std::optional<std::int64_t> alive_ns = stmt.column_optional_int64(1);
  const std::optional<std::int64_t> planned_end_ns = stmt.column_optional_int64(2);
  const std::optional<std::int64_t> last_ns = last_record_ns();
  const std::int64_t ended_ns = std::max({started_ns, alive_ns.value_or(started_ns), last_ns.value_or(started_ns)});
  std::string message =
      "the logger stopped without closing the run (killed, crashed, powered off, or unable to write to the store); ";
  message += last_ns ? "the record ends at +" + seconds_text(*last_ns - started_ns) : "nothing was recorded";
  if (alive_ns) message += ", the logger was last alive at +" + seconds_text(*alive_ns - started_ns);
  if (planned_end_ns && *planned_end_ns > ended_ns) {
    message += "; " + seconds_text(*planned_end_ns - ended_ns) + " of the planned " +
               seconds_text(*planned_end_ns - started_ns) + " are missing";
  } else {
    message += "; anything read after that is missing";
  }
  Transaction transaction(db_);
  db_.prepare("INSERT INTO events (run_id, device_id, t_ns, kind, message) VALUES (?, NULL, ?, 'interrupted', ?)")
      .bind_all(run_id_, ended_ns, message)
      .run();
  finish(RunStatus::kInterrupted, ended_ns);
  transaction.commit();
  spdlog::warn("{}: {}", dir_.string(), message);
}

RunStore RunStore::open(const fs::path& run_dir, bool writable) {
  if (!holds_run(run_dir)) throw StorageError("'" + run_dir.string() + "' holds no bosfuse run");
  refuse_newer_schema(run_dir);
  if (stored_status(run_dir) == RunStatus::kRunning) close_if_abandoned(run_dir);
  RunStore store(run_dir, writable ? Database::Mode::kReadWrite : Database::Mode::kReadOnly);
  if (writable) migrate(store.db_);
  store.run_id_ = store.run().id;
  return store;
}

RunStore RunStore::open_as_found(const fs::path& run_dir) {
  if (!holds_run(run_dir)) throw StorageError("'" + run_dir.string() + "' holds no bosfuse run");
  refuse_newer_schema(run_dir);
  RunStore store(run_dir, Database::Mode::kReadOnly);
  store.run_id_ = store.run().id;
  return store;
}

bool RunStore::abandoned(const fs::path& run_dir) {
  if (stored_status(run_dir) != RunStatus::kRunning) return false;
  try {
    return RunLock::try_acquire(run_dir).has_value();  // released again at once
  } catch (const StorageError&) {
    return false;  // cannot be checked (a read-only folder)
  }
}

// A `running` run nobody holds the lock of has lost its logger. A reader
// that may not write (a read-only copy of a run) only says so.
void RunStore::close_if_abandoned(const fs::path& run_dir) {
  std::optional<RunLock> lock;
  try {
    lock = RunLock::try_acquire(run_dir);
  } catch (const StorageError& e) {
    spdlog::warn("{}: the run is marked running, but it cannot be checked ({})", run_dir.string(), e.what());
    return;
  }
  if (!lock) return;  // being recorded right now
  // A dead logger's disk reserve: its room is what lets a full disk take
  // the run's closing account.
  std::error_code ignored;
  fs::remove(run_dir / SpaceReserve::kFileName, ignored);
  RunStore store(run_dir, Database::Mode::kReadWrite);
  migrate(store.db_);
  store.run_id_ = store.run().id;
  if (store.run().status == RunStatus::kRunning) store.close_interrupted();
}

std::int64_t RunStore::insert_run(const RunInfo& info) {
  if (!(info.time_scale > 0) || !std::isfinite(info.time_scale)) {
    throw StorageError("a run's time scale must be a positive number, not " + std::to_string(info.time_scale));
  }
  db_.prepare(
         "INSERT INTO runs (name, started_ns, config_toml, status, time_scale, origin_event) "
         "VALUES (?, ?, ?, 'running', ?, ?)")
      .bind_all(info.name, info.started_ns, info.config_toml, info.time_scale, info.origin_event)
      .run();
  return db_.last_insert_rowid();
}

RunInfo RunStore::run() const {
  // A store of an older schema opened read-only has neither column: it was
  // recorded in real time from its first sample.
  auto stmt = db_.prepare(schema_version(db_) >= 4 ? "SELECT id, name, started_ns, ended_ns, config_toml, status, "
                                                     "time_scale, origin_event FROM runs ORDER BY id LIMIT 1"
                                                   : "SELECT id, name, started_ns, ended_ns, config_toml, status, "
                                                     "1.0, NULL FROM runs ORDER BY id LIMIT 1");
  if (!stmt.step()) throw StorageError("run store '" + db_.path() + "' has no run");
  return read_run(stmt);
}

std::int64_t RunStore::add_device(const DeviceInfo& device) {
  db_.prepare(
         "INSERT INTO devices (run_id, name, kind, profile, address) VALUES (?, ?, ?, ?, ?) "
         "ON CONFLICT (run_id, name) DO UPDATE SET kind = excluded.kind, profile = excluded.profile, "
         "address = excluded.address")
      .bind_all(run_id_, device.name, device.kind, device.profile, device.address)
      .run();
  auto stmt = db_.prepare("SELECT id FROM devices WHERE run_id = ? AND name = ?");
  stmt.bind(1, run_id_).bind(2, device.name).step();
  return stmt.column_int64(0);
}

std::int64_t RunStore::add_channel(const ChannelInfo& channel) {
  db_.prepare(
         "INSERT INTO channels (device_id, name, kind, unit, tc_type, image_x_px, image_y_px, resolution) "
         "VALUES (?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (device_id, name) DO UPDATE SET kind = excluded.kind, "
         "unit = excluded.unit, tc_type = excluded.tc_type, image_x_px = excluded.image_x_px, "
         "image_y_px = excluded.image_y_px, resolution = excluded.resolution")
      .bind_all(channel.device_id, channel.name, channel.kind, channel.unit, channel.tc_type, channel.image_x_px,
                channel.image_y_px, channel.resolution)
      .run();
  auto stmt = db_.prepare("SELECT id FROM channels WHERE device_id = ? AND name = ?");
  stmt.bind(1, channel.device_id).bind(2, channel.name).step();
  return stmt.column_int64(0);
}

void RunStore::write_samples(std::span<const Sample> samples) {
  if (samples.empty()) return;
  if (!insert_sample_) {
    insert_sample_.emplace(db_.prepare(
        "INSERT INTO samples (channel_id, t_ns, device_t_ns, value, raw, status) VALUES (?, ?, ?, ?, ?, ?)"));
  }
  Transaction transaction(db_);
  for (const Sample& s : samples) {
    insert_sample_->bind_all(s.channel_id, s.t_ns, s.device_t_ns,
                             s.status == SampleStatus::kOk ? s.value : std::nullopt, s.raw, static_cast<int>(s.status));
    insert_sample_->run();
  }
  transaction.commit();
}

void RunStore::write_events(std::span<const Event> events) {
  if (events.empty()) return;
  auto stmt = db_.prepare("INSERT INTO events (run_id, device_id, t_ns, kind, message) VALUES (?, ?, ?, ?, ?)");
  Transaction transaction(db_);
  for (const Event& e : events) {
    stmt.bind_all(run_id_, e.device_id, e.t_ns, e.kind, e.message);
    stmt.run();
  }
  transaction.commit();
}

namespace {

constexpr const char* kInsertFrame =
    "INSERT INTO frames (device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, is_reference, "
    "arrival_ns) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)";

void insert_frame(Statement& stmt, const FrameRecord& frame) {
  stmt.bind_all(frame.device_id, frame.t_ns, frame.device_t_ns, frame.path, frame.width_px, frame.height_px,
                frame.bit_depth, frame.is_reference ? 1 : 0, frame.arrival_ns);
  stmt.run();
}

}  // namespace

std::int64_t RunStore::add_frame(const FrameRecord& frame) {
  auto stmt = db_.prepare(kInsertFrame);
  insert_frame(stmt, frame);
  return db_.last_insert_rowid();
}

void RunStore::write_frames(std::span<const FrameRecord> frames) {
  if (frames.empty()) return;
  auto stmt = db_.prepare(kInsertFrame);
  Transaction transaction(db_);
  for (const FrameRecord& frame : frames) insert_frame(stmt, frame);
  transaction.commit();
}

void RunStore::set_planned_end(std::int64_t t_ns) {
  db_.prepare("UPDATE runs SET planned_end_ns = ? WHERE id = ?").bind_all(t_ns, run_id_).run();
}

void RunStore::mark_alive(std::int64_t t_ns) {
  db_.prepare("UPDATE runs SET alive_ns = ? WHERE id = ?").bind_all(t_ns, run_id_).run();
}

std::optional<std::int64_t> RunStore::last_record_ns() const {
  auto stmt = db_.prepare(
      "SELECT MAX(t) FROM (SELECT MAX(t_ns) AS t FROM samples UNION ALL SELECT MAX(t_ns) FROM frames "
      "UNION ALL SELECT MAX(t_ns) FROM events WHERE run_id = ?1)");
  stmt.bind(1, run_id_).step();
  return stmt.column_optional_int64(0);
}

void RunStore::finish(RunStatus status, std::int64_t ended_ns) {
  db_.prepare("UPDATE runs SET status = ?, ended_ns = ? WHERE id = ?")
      .bind_all(to_string(status), ended_ns, run_id_)
      .run();
}

std::optional<std::int64_t> RunStore::first_sample_ns() const {
  auto stmt = db_.prepare("SELECT MIN(t_ns) FROM samples");
  stmt.step();
  return stmt.column_optional_int64(0);
}

std::optional<std::int64_t> RunStore::marker_ns(const std::string& message) const {
  auto stmt = db_.prepare("SELECT MIN(t_ns) FROM events WHERE run_id = ? AND kind = 'marker' AND message = ?");
  stmt.bind_all(run_id_, message).step();
  return stmt.column_optional_int64(0);
}

std::vector<DeviceInfo> RunStore::devices() const {
  auto stmt = db_.prepare("SELECT id, name, kind, profile, address FROM devices WHERE run_id = ? ORDER BY id");
  stmt.bind(1, run_id_);
  std::vector<DeviceInfo> out;
  while (stmt.step()) {
    out.push_back(
        {stmt.column_int64(0), stmt.column_text(1), stmt.column_text(2), stmt.column_text(3), stmt.column_text(4)});
  }
  return out;
}

std::vector<ChannelInfo> RunStore::channels() const {
  // A store of an older schema opened read-only has no resolution column:
  // its channels' resolution is unknown.
  auto stmt = db_.prepare(fmt::format(
      "SELECT c.id, c.device_id, c.name, c.kind, c.unit, c.tc_type, c.image_x_px, c.image_y_px, {} "
      "FROM channels c JOIN devices d ON d.id = c.device_id WHERE d.run_id = ? ORDER BY c.id",
      schema_version(db_) >= 6 ? "c.resolution" : "NULL"));
  stmt.bind(1, run_id_);
  std::vector<ChannelInfo> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_int64(1), stmt.column_text(2), stmt.column_text(3),
                   stmt.column_text(4), stmt.column_optional_text(5), stmt.column_optional_double(6),
                   stmt.column_optional_double(7), stmt.column_optional_double(8)});
  }
  return out;
}

std::vector<Sample> RunStore::read_samples(std::int64_t channel_id, TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT channel_id, t_ns, device_t_ns, value, raw, status FROM samples "
      "WHERE channel_id = ? AND t_ns BETWEEN ? AND ? ORDER BY t_ns");
  stmt.bind(1, channel_id);
  bind_range(stmt, 2, range);
  std::vector<Sample> out;
  while (stmt.step()) out.push_back(read_sample(stmt));
  return out;
}

SampleColumns RunStore::read_sample_columns(std::int64_t channel_id) const {
  SampleColumns out;
  auto stmt = db_.prepare("SELECT t_ns, value, status FROM samples WHERE channel_id = ? ORDER BY t_ns");
  stmt.bind(1, channel_id);
  while (stmt.step()) {
    const std::int64_t t_ns = stmt.column_int64(0);
    const SampleStatus status = sample_status_from_code(stmt.column_int64(2));
    check_sample_value(channel_id, t_ns, status, !stmt.is_null(1));
    out.t_ns.push_back(t_ns);
    out.value.push_back(status == SampleStatus::kOk ? stmt.column_double(1) : NAN);
    out.status.push_back(status);
  }
  return out;
}

void RunStore::for_each_sample(const std::function<void(const Sample&)>& visit, TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT channel_id, t_ns, device_t_ns, value, raw, status FROM samples "
      "WHERE t_ns BETWEEN ? AND ? ORDER BY t_ns, channel_id, rowid");
  bind_range(stmt, 1, range);
  while (stmt.step()) visit(read_sample(stmt));
}

std::vector<Event> RunStore::events(TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT id, device_id, t_ns, kind, message FROM events WHERE run_id = ? AND t_ns BETWEEN ? AND ? "
      "ORDER BY t_ns, id");
  stmt.bind(1, run_id_);
  bind_range(stmt, 2, range);
  std::vector<Event> out;
  while (stmt.step()) out.push_back(read_event(stmt));
  return out;
}

std::vector<FrameRecord> RunStore::frames(TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT id, device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, is_reference FROM frames "
      "WHERE t_ns BETWEEN ? AND ? ORDER BY t_ns, id");
  bind_range(stmt, 1, range);
  std::vector<FrameRecord> out;
  while (stmt.step()) out.push_back(read_frame(stmt));
  return out;
}

std::vector<ChannelSummary> RunStore::channel_summaries() const {
  auto stmt = db_.prepare(
      "SELECT d.name, COUNT(s.t_ns), COALESCE(SUM(s.status = 0), 0), MIN(s.t_ns), MAX(s.t_ns), MIN(s.value), "
      "MAX(s.value) FROM channels c JOIN devices d ON d.id = c.device_id LEFT JOIN samples s ON s.channel_id = c.id "
      "WHERE c.id = ? GROUP BY c.id");
  std::vector<ChannelSummary> out;
  for (const ChannelInfo& channel : channels()) {
    stmt.bind(1, channel.id);
    stmt.step();
    out.push_back({channel, stmt.column_text(0), stmt.column_int64(1), stmt.column_int64(2),
                   stmt.column_optional_int64(3), stmt.column_optional_int64(4), stmt.column_optional_double(5),
                   stmt.column_optional_double(6)});
    stmt.reset();
  }
  return out;
}

}  // namespace bosfuse::storage
