#pragma once
// RunTail reads what a run committed after a point, in commit order, for a
// live reader that must see every row once (`bosfuse view`): samples by SQLite's rowid of
// `samples` (the table has no id column, and the rowid of an append-only
// table only grows), events and frames by their ids. A TailCursor is how
// far a reader got; it is what the live stream sends as its event id, so a
// client that reconnects continues exactly where it stopped.
//
// Why not RunStore: RunStore reads by experiment time, and a batch committed
// late may hold samples older than one committed before it; only the rowid
// says what is new. Each RunTail is its own read-only connection (SQLite WAL
// readers never block the logger), used from one thread.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "storage/database.h"
#include "storage/records.h"

namespace bosfuse::storage {

struct TailCursor {
  std::int64_t sample_rowid = 0;
  std::int64_t event_id = 0;
  std::int64_t frame_id = 0;

  bool operator==(const TailCursor&) const = default;
};

struct TailSample {
  std::int64_t rowid = 0;
  Sample sample;
};

class RunTail {
 public:
  explicit RunTail(const std::filesystem::path& run_dir);

  // The newest committed row of each table.
  TailCursor head();
  // At most `limit` rows after `after`, oldest first.
  std::vector<TailSample> samples_after(std::int64_t after_rowid, int limit);
  std::vector<Event> events_after(std::int64_t after_id, int limit);
  std::vector<FrameRecord> frames_after(std::int64_t after_id, int limit);
  // How many frames have an id up to `frame_id`.
  std::int64_t frame_count_through(std::int64_t frame_id);
  std::string run_status();

 private:
  Database db_;
  Statement head_;
  Statement samples_;
  Statement events_;
  Statement frames_;
  Statement frame_count_;
  Statement status_;
};

}  // namespace bosfuse::storage
