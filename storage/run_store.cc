#include "storage/run_store.h"

#include <system_error>

#include "storage/schema.h"

namespace bosfuse::storage {
namespace {

namespace fs = std::filesystem;

std::string database_path(const fs::path& dir) { return (dir / RunStore::kDatabaseFileName).string(); }

RunInfo read_run(Statement& stmt) {
  RunInfo run;
  run.id = stmt.column_int64(0);
  run.name = stmt.column_text(1);
  run.started_ns = stmt.column_int64(2);
  run.ended_ns = stmt.column_optional_int64(3);
  run.config_toml = stmt.column_text(4);
  run.status = run_status_from_string(stmt.column_text(5));
  return run;
}

Sample read_sample(const Statement& stmt) {
  return {stmt.column_int64(0),           stmt.column_int64(1),
          stmt.column_optional_int64(2),  stmt.column_optional_double(3),
          stmt.column_optional_double(4), static_cast<SampleStatus>(stmt.column_int64(5))};
}

void bind_range(Statement& stmt, int first_index, TimeRange range) {
  stmt.bind(first_index, range.from_ns).bind(first_index + 1, range.to_ns);
}

}  // namespace

RunStore::RunStore(fs::path dir, Database::Mode mode) : dir_(std::move(dir)), db_(database_path(dir_), mode) {}

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
    throw StorageError("'" + run_dir.string() + "' already holds a run; choose another folder or ask to append to it");
  }
  fs::create_directories(run_dir);
  RunStore store(run_dir, Database::Mode::kCreate);
  migrate(store.db_);
  if (existing) {
    const RunInfo previous = store.run();
    store.run_id_ = previous.id;
    store.db_.prepare("UPDATE runs SET status = 'running', ended_ns = NULL WHERE id = ?").bind(1, store.run_id_).run();
    const std::string how = previous.status == RunStatus::kRunning
                                ? "the previous session ended without closing the run"
                                : "after a " + std::string(to_string(previous.status)) + " session";
    const Event appended{0, std::nullopt, info.started_ns, "appended", "logging resumed in this run, " + how};
    store.write_events({&appended, 1});
  } else {
    store.run_id_ = store.insert_run(info);
  }
  return store;
}

RunStore RunStore::open(const fs::path& run_dir, bool writable) {
  if (!holds_run(run_dir)) throw StorageError("'" + run_dir.string() + "' holds no bosfuse run");
  RunStore store(run_dir, writable ? Database::Mode::kReadWrite : Database::Mode::kReadOnly);
  if (writable) migrate(store.db_);
  store.run_id_ = store.run().id;
  return store;
}

std::int64_t RunStore::insert_run(const RunInfo& info) {
  db_.prepare("INSERT INTO runs (name, started_ns, config_toml, status) VALUES (?, ?, ?, 'running')")
      .bind_all(info.name, info.started_ns, info.config_toml)
      .run();
  return db_.last_insert_rowid();
}

RunInfo RunStore::run() const {
  auto stmt = db_.prepare("SELECT id, name, started_ns, ended_ns, config_toml, status FROM runs ORDER BY id LIMIT 1");
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
         "INSERT INTO channels (device_id, name, kind, unit, tc_type, image_x_px, image_y_px) "
         "VALUES (?, ?, ?, ?, ?, ?, ?) ON CONFLICT (device_id, name) DO UPDATE SET kind = excluded.kind, "
         "unit = excluded.unit, tc_type = excluded.tc_type, image_x_px = excluded.image_x_px, "
         "image_y_px = excluded.image_y_px")
      .bind_all(channel.device_id, channel.name, channel.kind, channel.unit, channel.tc_type, channel.image_x_px,
                channel.image_y_px)
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
    "INSERT INTO frames (device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, is_reference) "
    "VALUES (?, ?, ?, ?, ?, ?, ?, ?)";

void insert_frame(Statement& stmt, const FrameRecord& frame) {
  stmt.bind_all(frame.device_id, frame.t_ns, frame.device_t_ns, frame.path, frame.width_px, frame.height_px,
                frame.bit_depth, frame.is_reference ? 1 : 0);
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

void RunStore::finish(RunStatus status, std::int64_t ended_ns) {
  db_.prepare("UPDATE runs SET status = ?, ended_ns = ? WHERE id = ?")
      .bind_all(to_string(status), ended_ns, run_id_)
      .run();
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
  auto stmt = db_.prepare(
      "SELECT c.id, c.device_id, c.name, c.kind, c.unit, c.tc_type, c.image_x_px, c.image_y_px "
      "FROM channels c JOIN devices d ON d.id = c.device_id WHERE d.run_id = ? ORDER BY c.id");
  stmt.bind(1, run_id_);
  std::vector<ChannelInfo> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_int64(1), stmt.column_text(2), stmt.column_text(3),
                   stmt.column_text(4), stmt.column_optional_text(5), stmt.column_optional_double(6),
                   stmt.column_optional_double(7)});
  }
  return out;
}

std::vector<Sample> RunStore::read_samples(std::int64_t channel_id, TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT channel_id, t_ns, device_t_ns, value, raw, status FROM samples "
      "WHERE channel_id = ? AND t_ns BETWEEN ? AND ? ORDER BY t_ns, rowid");
  stmt.bind(1, channel_id);
  bind_range(stmt, 2, range);
  std::vector<Sample> out;
  while (stmt.step()) out.push_back(read_sample(stmt));
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
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_optional_int64(1), stmt.column_int64(2), stmt.column_text(3),
                   stmt.column_text(4)});
  }
  return out;
}

std::vector<FrameRecord> RunStore::frames(TimeRange range) const {
  auto stmt = db_.prepare(
      "SELECT id, device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, is_reference FROM frames "
      "WHERE t_ns BETWEEN ? AND ? ORDER BY t_ns, id");
  bind_range(stmt, 1, range);
  std::vector<FrameRecord> out;
  while (stmt.step()) {
    out.push_back({stmt.column_int64(0), stmt.column_optional_int64(1), stmt.column_int64(2),
                   stmt.column_optional_int64(3), stmt.column_text(4), static_cast<int>(stmt.column_int64(5)),
                   static_cast<int>(stmt.column_int64(6)), static_cast<int>(stmt.column_int64(7)),
                   stmt.column_int64(8) != 0});
  }
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
