#pragma once
// A RunLock says that a logger is writing a run right now: an exclusive
// flock(2) on RUN/run.lock, held while the logger lives and released by the
// kernel however the process ends (exit, crash, kill -9). It is how the
// next command tells a run that is still being recorded (leave it alone;
// `view` may watch it) from one whose logger died (mark it interrupted and
// say what is missing), and how a second logger is kept out of a run.

#include <filesystem>
#include <optional>
#include <string>

namespace bosfuse::storage {

class RunLock {
 public:
  static constexpr const char* kFileName = "run.lock";

  // The lock, or nothing when another process holds it. Throws StorageError
  // when the lock file cannot be made at all (read-only folder).
  // `file_name` names another lock of the run (e.g. "process.lock", held
  // while a processing writes the run's results).
  static std::optional<RunLock> try_acquire(const std::filesystem::path& run_dir,
                                            const std::string& file_name = kFileName);
  // Who holds the lock, as its holder wrote it ("pid 1234 on host"), or "".
  static std::string holder(const std::filesystem::path& run_dir, const std::string& file_name = kFileName);

  RunLock(RunLock&& other) noexcept;
  RunLock& operator=(RunLock&& other) noexcept;
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;
  ~RunLock();  // releases the lock; never throws

 private:
  explicit RunLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace bosfuse::storage
