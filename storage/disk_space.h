#pragma once
// How much room the disk of a run has, and whether it is filling: the
// logger refuses to start a run on a disk with less than `[run]
// min_free_mb` free, and while it records it samples the free space every
// few seconds (DiskFillWatch) to warn, with an estimate of the time left,
// before the disk is full rather than after.

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <optional>
#include <string>

namespace bosfuse::storage {

// Bytes an unprivileged process may still write on the file system holding
// `path` (statvfs f_bavail), or on that of its nearest existing parent
// folder when `path` does not exist yet. Throws StorageError if none can
// be examined.
std::uint64_t free_bytes(const std::filesystem::path& path);

// "1.4 GB", "830 MB", "12 KB" (powers of 1024, as df -h counts): for messages.
std::string bytes_text(std::uint64_t bytes);

// What a DiskFillWatch is set up with.
struct DiskFillWatchOptions {
  std::uint64_t min_free_bytes = 100ull << 20;
  std::chrono::seconds warn_within{3600};
  std::chrono::seconds window{60};
  std::string Validate() const;  // empty when valid, else what is wrong
};

// Watches samples of a disk's free space. It says, once, when the disk
// begins to run short — less than `min_free_bytes` left, or full within
// `warn_within` at the rate it has been filling over the last `window` —
// and once when it no longer is (twice those margins, so a rate that
// hovers about the threshold does not repeat itself).
class DiskFillWatch {
 public:
  struct Change {
    bool short_of_space;  // true: it began; false: it ended
    std::string message;  // "the disk of the run has 80 MB free and is filling at 2 MB/s: full in about 40 s"
  };

  explicit DiskFillWatch(DiskFillWatchOptions options);

  // One sample: `free` bytes at `now`. Returns a change of state, if any.
  std::optional<Change> add(std::chrono::steady_clock::time_point now, std::uint64_t free);
  // The time left at the current rate; nothing while the disk is not filling.
  std::optional<std::chrono::seconds> time_to_full() const;
  bool short_of_space() const { return short_; }

 private:
  struct Reading {
    std::chrono::steady_clock::time_point t;
    std::uint64_t free;
  };
  double filling_bytes_per_s() const;  // 0 when not filling
  bool runs_short(double margin) const;
  std::string describe() const;
  std::string time_left_text() const;  // "40 s", "12 min", "3.2 h"

  DiskFillWatchOptions options_;
  std::deque<Reading> readings_;
  bool short_ = false;
};

}  // namespace bosfuse::storage
