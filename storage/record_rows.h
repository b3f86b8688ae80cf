#pragma once
// How a row of `samples`, `events` or `frames` becomes its record, for every
// reader inside storage/ (RunStore, RunTail): the column order is written
// once, and the SELECTs name their columns in this order. `first` is the
// column the record starts at (a reader may put e.g. a rowid before it).
// Also where a run's database file lies. Internal to storage/.

#include <filesystem>
#include <string>

#include "storage/database.h"
#include "storage/records.h"

namespace bosfuse::storage {

std::string database_path(const std::filesystem::path& run_dir);

// channel_id, t_ns, device_t_ns, value, raw, status (a code no status has throws).
Sample read_sample(const Statement& stmt, int first = 0);
// A stored sample has a value exactly when its status is kOk; anything else
// throws StorageError: the run store is damaged.
void check_sample_value(std::int64_t channel_id, std::int64_t t_ns, SampleStatus status, bool has_value);
// id, device_id, t_ns, kind, message
Event read_event(const Statement& stmt, int first = 0);
// id, device_id, t_ns, device_t_ns, path, width_px, height_px, bit_depth, is_reference
FrameRecord read_frame(const Statement& stmt, int first = 0);

}  // namespace bosfuse::storage
