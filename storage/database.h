#pragma once
// Database is a thin owner of one SQLite connection, in the style of
// SQLiteCpp: the sqlite3* handle lives in a unique_ptr with a deleter, and
// statements (storage/statement.h) are prepared from it once and rebound;
// a Transaction (storage/transaction.h) groups writes. Use it inside
// storage/ only; the rest of bosfuse talks to a RunStore. Errors become
// StorageError (storage/storage_error.h); destructors never throw. Another
// connection's write lock is waited for up to a timeout (5 s), and a wait
// can be cut short from another thread (a logger's bounded stop).
// SQLite's own header stays in storage/'s .cc files: the handles are only
// forward-declared here.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "storage/statement.h"
#include "storage/storage_error.h"

struct sqlite3;

namespace bosfuse::storage {

struct SqliteCloser {
  void operator()(sqlite3* db) const noexcept;
};

class Database {
 public:
  // kImmutable reads without locks and makes no -wal or -shm file: a glance
  // that leaves the run's folder exactly as it was (storage/output_path.h),
  // which may miss what a live writer has not checkpointed yet.
  enum class Mode { kReadOnly, kReadWrite, kCreate, kImmutable };

  static constexpr std::chrono::milliseconds kLockTimeout{5000};

  // Opens (or creates) the file, turns on WAL, foreign keys and a lock
  // timeout (kLockTimeout) so a reader and the writer of a live run do not
  // fail on locks.
  Database(const std::string& path, Mode mode);

  void execute(std::string_view sql);
  Statement prepare(std::string_view sql);
  std::int64_t last_insert_rowid() const;
  sqlite3* handle() const { return db_.get(); }
  const std::string& path() const { return path_; }

  // Every wait for another connection's lock gives up at `deadline`, even
  // within its timeout (time_point::max(): no deadline). Safe to call from
  // any thread, also while this connection is waiting.
  void give_up_lock_waits_at(std::chrono::steady_clock::time_point deadline);

 private:
  struct LockWait {
    std::chrono::milliseconds timeout = kLockTimeout;
    std::atomic<std::chrono::steady_clock::rep> give_up_at{std::chrono::steady_clock::time_point::max().time_since_epoch().count()};
    std::chrono::steady_clock::time_point started;  // of the wait under way
  };
  static int wait_for_lock(void* lock_wait, int attempts);

  std::string path_;
  // On the heap: SQLite keeps its address, and a Database may be moved.
  std::unique_ptr<LockWait> lock_wait_ = std::make_unique<LockWait>();
  std::unique_ptr<sqlite3, SqliteCloser> db_;
};

}  // namespace bosfuse::storage
