#include "storage/run_paths.h"

#include <algorithm>
#include <cstdio>

#include "storage/database.h"

namespace bosfuse::storage {
namespace fs = std::filesystem;
namespace {

bool is_control(char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; }

[[noreturn]] void refuse(std::string_view stored_path, const std::string& why) {
  throw StorageError("stored path '" + printable(stored_path) + "' refused: " + why);
}

// Component-wise, so /runs/a is not taken to contain /runs/ab.
bool is_within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // the empty last component of a path ending in '/'
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

}  // namespace

std::string printable(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (!is_control(c)) {
      out += c;
      continue;
    }
    char escaped[5];
    std::snprintf(escaped, sizeof escaped, "\\x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
    out += escaped;
  }
  return out;
}

fs::path resolve_in_run(const fs::path& run_dir, std::string_view stored_path) {
  if (stored_path.empty()) refuse(stored_path, "it is empty");
  if (std::any_of(stored_path.begin(), stored_path.end(), is_control)) {
    refuse(stored_path, "it holds a control character");
  }
  const fs::path relative(stored_path);
  if (relative.is_absolute() || relative.has_root_path()) refuse(stored_path, "it is absolute");
  for (const auto& part : relative) {
    if (part == "..") refuse(stored_path, "it has a '..' component");
  }
  std::error_code error;
  const fs::path root = fs::weakly_canonical(run_dir, error);
  const fs::path target = error ? fs::path() : fs::weakly_canonical(root / relative, error);
  if (error) refuse(stored_path, "it cannot be resolved in " + run_dir.string() + ": " + error.message());
  if (!is_within(target, root)) {
    refuse(stored_path, "a symlink along it leads outside the run folder " + root.string() + " (to " +
                            printable(target.string()) + ")");
  }
  return target;
}

}  // namespace bosfuse::storage
