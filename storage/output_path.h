#pragma once
// What a command may write. A run's own files are written only by its own
// logger (`acquire`, `replay`, `demo` recording it) and its own processing
// (`process`, `calibrate`, `mark`); no other output — an export, a report,
// an evaluation, a figure, a pattern, a new run — may land on them or inside
// them. Every output path a command is given (every -o, --out, --json,
// --csv, --fields, --map) goes through check_output_path() before anything
// is written, and storage::PartialFile (storage/partial_file.h), the one way
// commands write files, checks its destination again.
//
// A run's own files, for a folder holding run.sqlite: the run store and its
// SQLite companions (run.sqlite-wal, -shm, -journal), its locks (run.lock,
// process.lock), the folders frames/, fields/ and masks/ with everything in
// them, every other file or top-level folder the store's rows name (frame
// and field paths, the mask of a stored processing), and the run folder
// itself. A new file or folder beside them (RUN/report/, RUN/fields.h5) is
// not one of them and is allowed.
//
// The check does not need to know which run is meant: the output is resolved
// (symlinks, `.` and `..`, as weakly_canonical does) and every folder from
// it up to the root that holds run.sqlite is a run whose own files it must
// not be, so `RUN/./run.sqlite`, `RUN/frames/../run.sqlite`, a symlink to
// the store and `RUN/frames/new.csv` are all refused.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "storage/database.h"

namespace bosfuse::storage {

// An output refused because it is (or lies inside) a run's own file.
class OutputRefused : public StorageError {
 public:
  using StorageError::StorageError;
};

struct RunOwnedPath {
  std::filesystem::path run_dir;  // the run folder (resolved)
  std::string what;               // "its run store, run.sqlite", "inside its folder frames/", ...
};

// Which run's own file or folder `output` is (or lies inside), or nothing.
// `output` need not exist; a relative path is taken from the working folder.
std::optional<RunOwnedPath> run_owned_path(const std::filesystem::path& output);

// Throws OutputRefused naming `option` (may be empty), the path as given,
// what it is and the run, when run_owned_path(output) finds one.
void check_output_path(const std::filesystem::path& output, std::string_view option = {});

// For the folder of a new run (acquire, replay, demo): check_output_path(),
// except that a folder already holding a run is refused as one that holds
// a run (which a new run must not overwrite), not as a run's own folder.
void check_new_run_folder(const std::filesystem::path& run_dir, std::string_view option = {});

}  // namespace bosfuse::storage
