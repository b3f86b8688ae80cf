#include "storage/record_rows.h"

#include "storage/run_store.h"

namespace bosfuse::storage {

std::string database_path(const std::filesystem::path& run_dir) {
  return (run_dir / RunStore::kDatabaseFileName).string();
}

Sample read_sample(const Statement& stmt, int first) {
  return {stmt.column_int64(first),
          stmt.column_int64(first + 1),
          stmt.column_optional_int64(first + 2),
          stmt.column_optional_double(first + 3),
          stmt.column_optional_double(first + 4),
          sample_status_from_code(stmt.column_int64(first + 5))};
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
          stmt.column_int64(first + 8) != 0};
}

}  // namespace bosfuse::storage
