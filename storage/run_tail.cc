#include "storage/run_tail.h"

#include "storage/record_rows.h"
#include "storage/schema.h"

namespace bosfuse::storage {
namespace {

// A store of a newer schema is refused before any statement is prepared.
Database open_known_schema(const std::filesystem::path& run_dir) {
  Database db(database_path(run_dir), Database::Mode::kReadOnly);
  require_known_schema(db);
  return db;
}

}  // namespace

RunTail::RunTail(const std::filesystem::path& run_dir)
    : db_(open_known_schema(run_dir)),
      head_(db_.prepare("SELECT (SELECT COALESCE(MAX(rowid), 0) FROM samples), "
                        "(SELECT COALESCE(MAX(id), 0) FROM events), (SELECT COALESCE(MAX(id), 0) FROM frames)")),
      samples_(db_.prepare("SELECT rowid, channel_id, t_ns, device_t_ns, value, raw, status FROM samples "
                           "WHERE rowid > ? ORDER BY rowid LIMIT ?")),
      events_(db_.prepare("SELECT id, device_id, t_ns, kind, message FROM events WHERE id > ? ORDER BY id LIMIT ?")),
      frames_(db_.prepare("SELECT id, device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, "
                          "is_reference FROM frames WHERE id > ? ORDER BY id LIMIT ?")),
      frame_count_(db_.prepare("SELECT COUNT(*) FROM frames WHERE id <= ?")),
      status_(db_.prepare("SELECT status FROM runs ORDER BY id LIMIT 1")) {}

TailCursor RunTail::head() {
  head_.reset();
  head_.step();
  TailCursor cursor{head_.column_int64(0), head_.column_int64(1), head_.column_int64(2)};
  head_.reset();  // ends the read transaction, so the writer's WAL can be checkpointed
  return cursor;
}

std::vector<TailSample> RunTail::samples_after(std::int64_t after_rowid, int limit) {
  std::vector<TailSample> rows;
  samples_.reset();
  samples_.bind(1, after_rowid).bind(2, limit);
  while (samples_.step()) {
    rows.push_back({samples_.column_int64(0), read_sample(samples_, 1)});
  }
  samples_.reset();
  return rows;
}

std::vector<Event> RunTail::events_after(std::int64_t after_id, int limit) {
  std::vector<Event> rows;
  events_.reset();
  events_.bind(1, after_id).bind(2, limit);
  while (events_.step()) rows.push_back(read_event(events_));
  events_.reset();
  return rows;
}

std::vector<FrameRecord> RunTail::frames_after(std::int64_t after_id, int limit) {
  std::vector<FrameRecord> rows;
  frames_.reset();
  frames_.bind(1, after_id).bind(2, limit);
  while (frames_.step()) rows.push_back(read_frame(frames_));
  frames_.reset();
  return rows;
}

std::int64_t RunTail::frame_count_through(std::int64_t frame_id) {
  frame_count_.reset();
  frame_count_.bind(1, frame_id).step();
  const std::int64_t count = frame_count_.column_int64(0);
  frame_count_.reset();
  return count;
}

std::string RunTail::run_status() {
  status_.reset();
  std::string status = status_.step() ? status_.column_text(0) : "unknown";
  status_.reset();
  return status;
}

}  // namespace bosfuse::storage
