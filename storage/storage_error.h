#pragma once
// StorageError is what every failure of the run store throws: SQLite's
// message with the statement that failed, SQLite's extended result code and
// the errno behind it, so a caller can tell a full disk or a held lock from a
// bug. Catch it (include only this header) wherever a storage failure must
// be reported or reacted to; it needs no SQLite to be caught.

#include <stdexcept>
#include <string>

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

}  // namespace bosfuse::storage
