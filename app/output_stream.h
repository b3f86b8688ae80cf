#pragma once
// Where a command writes the one file it produces (`-o FILE`, `--json
// FILE`): a file, or standard output when the name is "-", the same in
// every subcommand. Standard output then holds the data and nothing else,
// so the command's other text — the human-readable result that normally
// goes there, the "wrote FILE" line — moves to standard error as a
// message (which --quiet silences). A write that fails (a full disk) is an
// error naming the destination, not a short file and exit status 0.
// A file is written through storage::PartialFileStream: under a temporary
// name, renamed onto the destination by close(), so a failed command
// leaves an older file of that name whole; and it is never one of a run's
// own files (storage/output_path.h), refused before any work is done.
// Outputs that cannot go to a pipe — images and HDF5, whose format comes
// from the file name, and run folders — refuse "-" with the reason.
//
// Header-only: fuzz/fit_csv_fuzz.cc compiles app/cmd_fit.cc, which uses
// it, without the rest of the command line.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "report/figures.h"
#include "storage/output_path.h"
#include "storage/partial_file.h"

namespace bosfuse::app {

inline bool names_standard_output(std::string_view path) { return path == "-"; }

// Throws storage::OutputRefused when `path` is one of a run's own files or
// folders (standard output, and an option not given, are none). Commands
// call it for every output before they start work; the writers check again.
inline void check_output(std::string_view path, std::string_view option) {
  if (!path.empty() && !names_standard_output(path)) storage::check_output_path(std::string(path), option);
}

// The folder of a new run: none of a run's own, and no run already.
inline void check_new_run_output(std::string_view path, std::string_view option) {
  if (!path.empty() && !names_standard_output(path)) storage::check_new_run_folder(std::string(path), option);
}

// A figure named by its PNG is also drawn as the SVG beside it (report/figures.h).
inline void check_figure_output(std::string_view png_path, std::string_view option) {
  report::figure_base(png_path);  // a figure is named by its PNG: said before anything is written
  check_output(png_path, option);
  check_output(std::filesystem::path(png_path).replace_extension(".svg").string(), option);
}

// Throws for "-" on an option whose output needs a real file or folder.
inline void refuse_standard_output(std::string_view path, std::string_view option, std::string_view why) {
  if (names_standard_output(path)) {
    throw std::runtime_error(fmt::format("{} cannot be standard output ('-'): {}", option, why));
  }
}

// The human-readable result: standard output, unless the data took it.
inline std::ostream& text_stream(bool standard_output_holds_data) {
  if (!standard_output_holds_data) return std::cout;
  if (spdlog::should_log(spdlog::level::info)) return std::cerr;
  static std::ostream discard(nullptr);  // --quiet: a stream without a buffer writes nothing
  return discard;
}

class OutputStream {
 public:
  // Creates the temporary file now, so a path that cannot be written (or
  // that a run owns) fails before any work is done; the destination itself
  // is replaced only by close().
  explicit OutputStream(std::string path, std::string_view option = {}) : path_(std::move(path)) {
    if (to_standard_output()) return;
    check_output(path_, option);
    file_.emplace(path_);
  }

  bool to_standard_output() const { return names_standard_output(path_); }
  std::ostream& stream() { return file_ ? file_->stream() : std::cout; }

  // Flushes and checks every write, then puts the file in place; a file
  // says where it went.
  void close() {
    if (!file_) {
      std::cout.flush();
      if (!std::cout) throw std::runtime_error("could not write to standard output");
      return;
    }
    file_->close();
    spdlog::info("wrote {}", path_);
  }

 private:
  std::string path_;
  std::optional<storage::PartialFileStream> file_;
};

}  // namespace bosfuse::app
