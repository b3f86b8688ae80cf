#include "app/run_argument.h"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <system_error>

#include "storage/run_store.h"

namespace bosfuse::app {

namespace fs = std::filesystem;

std::string resolve_run_argument(std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return "no such folder: '" + path + "'";
  if (fs::is_directory(status)) return "";
  const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
  // Only the file's presence: whether it holds a readable run is the
  // store's to say, with its own message.
  if (!fs::exists(parent / storage::RunStore::kDatabaseFileName, ec)) {
    return "'" + path + "' is a file, not a run folder (a run is the folder holding run.sqlite)";
  }
  path = parent.string();
  return "";
}

CLI::Validator run_folder_argument() {
  return CLI::Validator([](std::string& path) { return resolve_run_argument(path); }, "RUN", "run folder");
}

}  // namespace bosfuse::app
