#pragma once
// A SpaceReserve is a file of a few hundred KB the logger keeps in the run
// folder while it records (RUN/run.reserve), so that a disk that fills up
// still has room for the run's own account of what happened: deleting the
// file at a stop that finds the disk full frees enough for the fault
// events, the count of records lost and the `interrupted` status. It is
// spent only there, not on more samples, which would fill it at once and
// leave the run saying nothing. The file is made with its blocks allocated
// (posix_fallocate, else written), never sparse, and deleted when the
// reserve ends. One left behind by a logger that was killed is removed by
// the next command that closes the run (RunStore::open).

#include <cstddef>
#include <filesystem>

namespace bosfuse::storage {

class SpaceReserve {
 public:
  static constexpr const char* kFileName = "run.reserve";

  // Makes RUN/run.reserve of `bytes`; throws StorageError (disk full
  // already, read-only folder) with no file left behind.
  SpaceReserve(const std::filesystem::path& run_dir, std::size_t bytes);
  ~SpaceReserve();  // deletes the file; never throws
  SpaceReserve(SpaceReserve&& other) noexcept;
  SpaceReserve& operator=(SpaceReserve&&) = delete;
  SpaceReserve(const SpaceReserve&) = delete;
  SpaceReserve& operator=(const SpaceReserve&) = delete;

  // Deletes the file, so its space is free now; true if it was still there.
  bool release() noexcept;
  bool held() const { return !path_.empty(); }
  std::size_t bytes() const { return bytes_; }

 private:
  std::filesystem::path path_;  // empty once released
  std::size_t bytes_ = 0;
};

}  // namespace bosfuse::storage
