#include "storage/record_rows.h"

#include "storage/run_store.h"

namespace bosfuse::storage {

std::string database_path(const std::filesystem::path& run_dir) {
  return (run_dir / RunStore::kDatabaseFileName).string();
}

// The schema's CHECK (a value exactly when the status is ok) is checked
// again here: a file whose schema text was damaged no longer enforces it,
// and every reader relies on it.
Sample read_sample(const Statement& stmt, int first) {
  Sample sample{stmt.column_int64(first),
                stmt.column_int64(first + 1),
                stmt.column_optional_int64(first + 2),
                stmt.column_optional_double(first + 3),
                stmt.column_optional_double(first + 4),
                sample_status_from_code(stmt.column_int64(first + 5))};
  check_sample_value(sample.channel_id, sample.t_ns, sample.status, sample.value.has_value());
  return sample;
}

void check_sample_value(std::int64_t channel_id, std::int64_t t_ns, SampleStatus status, bool has_value) {
  if (has_value == (status == SampleStatus::kOk)) return;
  throw StorageError("a sample of channel " + std::to_string(channel_id) + " at " + std::to_string(t_ns) +
                     " ns has status " + std::string(to_string(status)) + (has_value ? " and a value" : " and no value") +
                     ": the run store is damaged");
}

Event read_event(const Statement& stmt, int first) {
  return {stmt.column_int64(first), stmt.column_optional_int64(first + 1), stmt.column_int64(first + 2),
          stmt.column_text(first + 3), stmt.column_text(first + 4)};
}

FrameRecord read_frame(const Statement& stmt, int first) {
  return {stmt.column_int64(first),
          stmt.column_optional_int64(first + 1),
          stmt.column_int64(first + 2),
          stmt.column_optional_int64(first + 3),
          stmt.column_text(first + 4),
          static_cast<int>(stmt.column_int64(first + 5)),
          static_cast<int>(stmt.column_int64(first + 6)),
          static_cast<int>(stmt.column_int64(first + 7)),
          stmt.column_int64(first + 8) != 0,
          std::nullopt};  // arrival_ns: frames.arrival_ns is read only where asked for
}

}  // namespace bosfuse::storage
