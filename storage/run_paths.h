#pragma once
// Where a path stored in a run store lies on disk. A run store is input like
// any other file: a frames or fields row may say `../x.png`, `/etc/passwd`,
// or name a symlink that leads out of the run. Every path read from a run
// store becomes a file path only through resolve_in_run(), which keeps it
// inside the run folder or refuses it by name, so no command (process,
// report, replay) ever reads a file outside the run it was given.

#include <filesystem>
#include <string>
#include <string_view>

namespace bosfuse::storage {

// The file `stored_path` (relative to the run folder, as the run store holds
// it) names, with symlinks resolved. Throws StorageError naming the stored
// path and why when it is empty, holds a NUL or other control character, is
// absolute, has a `..` component, or leads outside `run_dir` through a
// symlink anywhere along it. A symlink that stays inside the run is fine; the
// file need not exist (a missing frame is the caller's to report).
std::filesystem::path resolve_in_run(const std::filesystem::path& run_dir, std::string_view stored_path);

// `text` with control characters as \xNN, for messages that quote a stored
// string without letting it move the terminal's cursor.
std::string printable(std::string_view text);

}  // namespace bosfuse::storage
