#pragma once
// How a command writes a file: under a temporary name beside its
// destination, renamed into place (one rename(2), atomic on one
// filesystem) only once the whole file is written. An output that fails
// half-way — a full disk, a broken input, an exception, Ctrl-C — leaves the
// destination as it was, byte for byte, never a half-written file, and the
// temporary is removed when its owner goes without a commit. Every
// destination is first checked by check_output_path() (storage/
// output_path.h), so no command's output can replace a run's own files.
//
// PartialFile names the temporary for a writer that opens files itself
// (HDF5, PLplot, OpenCV); PartialFileStream is an std::ostream on one;
// PartialFolder stages a set of files (a report) and moves them in together.
// A process killed between writing and renaming leaves a hidden
// `.NAME.partial-PID-N.EXT` beside the destination, never a damaged one.

#include <filesystem>
#include <fstream>
#include <ostream>
#include <vector>

namespace bosfuse::storage {

class PartialFile {
 public:
  // Throws OutputRefused for a run's own file. The temporary keeps the
  // destination's extension (a writer may choose its format by it). A
  // destination that is a symlink is written through: its target is
  // replaced, the link stays. One that exists and is no regular file (a
  // device such as /dev/null, a pipe) is written directly, as it cannot be
  // replaced.
  explicit PartialFile(const std::filesystem::path& destination);
  ~PartialFile();  // removes the temporary unless committed; never throws
  PartialFile(const PartialFile&) = delete;
  PartialFile& operator=(const PartialFile&) = delete;

  const std::filesystem::path& path() const { return temporary_; }  // where to write
  const std::filesystem::path& destination() const { return destination_; }
  // Renames the temporary onto the destination; throws naming the
  // destination when it cannot (the temporary is then removed).
  void commit();

 private:
  std::filesystem::path destination_;
  std::filesystem::path temporary_;
  bool committed_ = false;
};

// An output file stream on a PartialFile: close() flushes, checks every
// write and renames the file into place.
class PartialFileStream {
 public:
  explicit PartialFileStream(const std::filesystem::path& destination);  // throws when it cannot be created
  std::ostream& stream() { return out_; }
  // Throws "could not write 'DESTINATION'" when a write failed.
  void close();

 private:
  PartialFile file_;
  std::ofstream out_;
};

// A folder of files staged together: written into path() (a hidden folder
// inside the destination folder, so every rename stays on one filesystem)
// and moved into the destination by commit(), each replacing the file of
// the same name. Until then the destination's old files are untouched;
// without a commit the staging folder is removed, and the destination too
// when this created it and it is still empty.
class PartialFolder {
 public:
  // Throws OutputRefused for a run's own folder, std::runtime_error when
  // the folder cannot be created.
  explicit PartialFolder(const std::filesystem::path& destination);
  ~PartialFolder();
  PartialFolder(const PartialFolder&) = delete;
  PartialFolder& operator=(const PartialFolder&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }
  // Moves every file of the staging folder into the destination; returns
  // where each went.
  std::vector<std::filesystem::path> commit();

 private:
  std::filesystem::path destination_;
  std::filesystem::path staging_;
  bool created_destination_ = false;
  bool committed_ = false;
};

}  // namespace bosfuse::storage
