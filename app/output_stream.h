#pragma once
// Where a command writes the one file it produces (`-o FILE`, `--json
// FILE`): a file, or standard output when the name is "-", the same in
// every subcommand. Standard output then holds the data and nothing else,
// so the command's other text — the human-readable result that normally
// goes there, the "wrote FILE" line — moves to standard error as a
// message (which --quiet silences). A write that fails (a full disk) is an
// error naming the destination, not a short file and exit status 0.
// Outputs that cannot go to a pipe — images and HDF5, whose format comes
// from the file name, and run folders — refuse "-" with the reason.
//
// Header-only: fuzz/fit_csv_fuzz.cc compiles app/cmd_fit.cc, which uses
// it, without the rest of the command line.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace bosfuse::app {

inline bool names_standard_output(std::string_view path) { return path == "-"; }

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
  // Creates (or truncates) the file now, so a path that cannot be written
  // fails before any work is done.
  explicit OutputStream(std::string path) : path_(std::move(path)) {
    if (to_standard_output()) return;
    file_.open(path_);
    if (!file_) throw std::runtime_error("cannot write '" + path_ + "'");
  }

  bool to_standard_output() const { return names_standard_output(path_); }
  std::ostream& stream() { return to_standard_output() ? std::cout : file_; }

  // Flushes and checks every write; a file says where it went.
  void close() {
    std::ostream& out = stream();
    out.flush();
    if (!out) {
      throw std::runtime_error(to_standard_output() ? std::string("could not write to standard output")
                                                    : "could not write '" + path_ + "'");
    }
    if (to_standard_output()) return;
    file_.close();
    if (!file_) throw std::runtime_error("could not write '" + path_ + "'");
    spdlog::info("wrote {}", path_);
  }

 private:
  std::string path_;
  std::ofstream file_;
};

}  // namespace bosfuse::app
