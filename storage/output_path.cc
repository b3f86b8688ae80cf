#include "storage/output_path.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <array>
#include <iterator>
#include <set>

#include "storage/run_lock.h"
#include "storage/run_paths.h"
#include "storage/run_store.h"
#include "storage/space_reserve.h"

namespace bosfuse::storage {
namespace fs = std::filesystem;
namespace {

struct OwnName {
  std::string_view name;
  std::string_view what;
};

// The run's own files beside run.sqlite: SQLite's companions (the WAL, its
// index and a rollback journal) and the locks (RunLock; "process.lock" is
// the one pipeline/process.cc holds while it writes results), and the
// room a logger keeps for its last records on a full disk (SpaceReserve).
constexpr std::array<OwnName, 7> kOwnFiles{{{"run.sqlite", "its run store"},
                                            {"run.sqlite-wal", "its run store's write-ahead log"},
                                            {"run.sqlite-shm", "its run store's shared-memory index"},
                                            {"run.sqlite-journal", "its run store's rollback journal"},
                                            {RunLock::kFileName, "its logger's lock"},
                                            {"process.lock", "its processing's lock"},
                                            {SpaceReserve::kFileName, "its logger's reserve of disk space"}}};
// Folders the run fills: frames the logger records, fields `process`
// writes, masks a processing copies in.
constexpr std::array<std::string_view, 3> kOwnFolders{"frames", "fields", "masks"};

// `path` made absolute with symlinks, `.` and `..` resolved as far as it
// exists, and no trailing separator (so RUN/ is the folder RUN).
fs::path resolved(const fs::path& path) {
  std::error_code error;
  fs::path out = fs::weakly_canonical(fs::absolute(path), error);
  if (error) out = fs::absolute(path).lexically_normal();
  if (out.filename().empty() && out.has_parent_path() && out != out.root_path()) out = out.parent_path();
  return out;
}

bool holds_run_store(const fs::path& dir) {
  std::error_code error;
  const fs::path store = dir / RunStore::kDatabaseFileName;
  return fs::exists(fs::symlink_status(store, error));
}

// The first component of every path the store's rows name (frames, fields,
// a stored processing's mask): a top-level file or folder the run owns.
// Best effort: a store that cannot be read still has its fixed names. Read
// immutable, so checking an output leaves no -wal or -shm file in the run.
std::set<std::string> stored_top_level_names(const fs::path& run_dir) {
  std::set<std::string> names;
  try {
    Database db((run_dir / RunStore::kDatabaseFileName).string(), Database::Mode::kImmutable);
    for (const char* sql : {"SELECT path FROM frames", "SELECT path FROM fields", "SELECT path FROM staged_fields",
                            "SELECT json_extract(settings_json, '$.mask') FROM processings"}) {
      try {
        Statement rows = db.prepare(sql);
        while (rows.step()) {
          const auto stored = rows.column_optional_text(0);
          if (!stored || stored->empty()) continue;
          const fs::path p = fs::path(*stored).lexically_normal();
          if (!p.empty() && !p.is_absolute() && *p.begin() != "..") names.insert(p.begin()->string());
        }
      } catch (const StorageError&) {
        // an older schema without this table
      }
    }
  } catch (const std::exception& e) {
    spdlog::debug("output check: the store of {} could not be read ({}); its fixed names still count", run_dir.string(),
                  e.what());
  }
  return names;
}

// What `relative` (the output below `run_dir`) is of that run, or "".
std::string owned_within(const fs::path& run_dir, const fs::path& relative) {
  if (relative.empty() || relative == ".") return "the run folder itself";
  const std::string first = relative.begin()->string();
  const bool nested = std::next(relative.begin()) != relative.end();
  for (const auto& own : kOwnFiles) {
    if (first == own.name) return std::string(own.what) + ", " + first;
  }
  for (const auto& folder : kOwnFolders) {
    if (first == folder) return fmt::format("{}its folder {}/", nested ? "inside " : "", first);
  }
  if (stored_top_level_names(run_dir).count(first) > 0) {
    return nested ? fmt::format("inside the folder {}/, which its store names", first)
                  : fmt::format("the file {}, which its store names", first);
  }
  return "";
}

}  // namespace

std::optional<RunOwnedPath> run_owned_path(const fs::path& output) {
  const fs::path target = resolved(output);
  for (fs::path dir = target;; dir = dir.parent_path()) {
    if (holds_run_store(dir)) {
      const fs::path relative = target.lexically_relative(dir);
      if (std::string what = owned_within(dir, relative); !what.empty()) return RunOwnedPath{dir, what};
    }
    if (dir == dir.root_path() || !dir.has_parent_path()) break;
  }
  return std::nullopt;
}

void check_output_path(const fs::path& output, std::string_view option) {
  const auto owned = run_owned_path(output);
  if (!owned) return;
  const std::string given = printable(output.string());
  throw OutputRefused(
      fmt::format("refusing to write {}'{}': the run {} owns it ({}), and a run's own files and folders are never "
                  "overwritten; choose a path outside them (a new file or folder beside them, such as {}, is fine)",
                  option.empty() ? "" : std::string(option) + " ", given, printable(owned->run_dir.string()),
                  owned->what, printable((owned->run_dir / "report").string() + "/")));
}

void check_new_run_folder(const fs::path& run_dir, std::string_view option) {
  const fs::path target = resolved(run_dir);
  if (holds_run_store(target)) {
    throw OutputRefused(fmt::format(
        "refusing to write {}'{}': it already holds a run ({}), which a new run never overwrites; choose another "
        "folder, or append to that run where the command can (acquire --append)",
        option.empty() ? "" : std::string(option) + " ", printable(run_dir.string()), printable(target.string())));
  }
  check_output_path(run_dir, option);
}

}  // namespace bosfuse::storage
