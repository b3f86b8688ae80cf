#pragma once
// Database is a thin owner of one SQLite connection, in the style of
// SQLiteCpp: the sqlite3* handle lives in a unique_ptr with a deleter,
// statements are prepared once and rebound, and a Transaction rolls back in
// its destructor unless committed. Use it inside storage/ only; the rest of
// bosfuse talks to a RunStore. Errors become StorageError carrying SQLite's
// message, the statement that failed and SQLite's result code, so a caller
// can tell a full disk or a held lock from a bug; destructors never throw.
// Another connection's write lock is waited for up to a timeout (5 s), and a
// wait can be cut short from another thread (a logger's bounded stop).

#include <sqlite3.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace bosfuse::storage {

class StorageError : public std::runtime_error {
 public:
  // What a failure says about the store, for those who must react to it.
  enum class Kind {
    kOther,     // a refused statement, a damaged file, a bug
    kDiskFull,  // SQLITE_FULL, or the disk was found full (ENOSPC) on an I/O error
    kIoError,   // SQLITE_IOERR: the file system failed a read or write
    kLocked,    // SQLITE_BUSY / SQLITE_LOCKED: another connection held a lock past the timeout
  };

  using std::runtime_error::runtime_error;
  // `sqlite_code`: SQLite's extended result code; `system_errno`: the
  // errno of the failed system call behind it, if any.
  StorageError(const std::string& what, int sqlite_code, int system_errno = 0);

  int sqlite_code() const { return sqlite_code_; }
  Kind kind() const;
  // SQLite's words for the code ("database or disk is full"), without the
  // statement; empty when the error is not SQLite's.
  std::string reason() const;

 private:
  int sqlite_code_ = 0;
  int system_errno_ = 0;
};

struct SqliteCloser {
  void operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }
};
struct StatementFinalizer {
  void operator()(sqlite3_stmt* stmt) const noexcept { sqlite3_finalize(stmt); }
};

class Statement;

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

// A prepared statement. bind() indices start at 1 as in SQLite; step()
// returns true while rows are available and resets nothing by itself.
class Statement {
 public:
  Statement(sqlite3* db, std::string_view sql);

  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, static_cast<std::int64_t>(value)); }
  Statement& bind(int index, bool value) { return bind(index, value ? 1 : 0); }
  Statement& bind(int index, const std::string& value) { return bind(index, std::string_view(value)); }
  Statement& bind(int index, const char* value) { return bind(index, std::string_view(value)); }
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view value);
  Statement& bind(int index, std::nullopt_t);
  template <typename T>
  Statement& bind(int index, const std::optional<T>& value) {
    return value ? bind(index, *value) : bind(index, std::nullopt);
  }

  // Binds the arguments to parameters 1, 2, ... in order.
  template <typename... Args>
  Statement& bind_all(const Args&... args) {
    int index = 0;
    (bind(++index, args), ...);
    return *this;
  }

  bool step();   // true: a row is ready; false: done
  void run();    // step() for statements that return no rows, then reset()
  void reset();  // ready to run again; bindings are kept

  bool is_null(int column) const;
  std::int64_t column_int64(int column) const;
  double column_double(int column) const;
  std::string column_text(int column) const;
  std::optional<double> column_optional_double(int column) const;
  std::optional<std::int64_t> column_optional_int64(int column) const;
  std::optional<std::string> column_optional_text(int column) const;

 private:
  void check(int rc, const char* what) const;

  sqlite3* db_;
  std::unique_ptr<sqlite3_stmt, StatementFinalizer> stmt_;
};

// BEGIN IMMEDIATE on construction; ROLLBACK in the destructor unless commit()
// was called, so an exception between the two loses nothing already committed
// and leaves no half-written batch behind.
class Transaction {
 public:
  explicit Transaction(Database& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  void commit();

 private:
  Database& db_;
  bool committed_ = false;
};

}  // namespace bosfuse::storage
