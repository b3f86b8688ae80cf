#include "storage/storage_error.h"

#include <sqlite3.h>

#include <cerrno>
#include <string>

#include "storage/sqlite_failure.h"

namespace bosfuse::storage {

void throw_last_error(sqlite3* db, const std::string& what) {
  if (!db) throw StorageError(what + ": out of memory", SQLITE_NOMEM);
  throw StorageError(what + ": " + sqlite3_errmsg(db), sqlite3_extended_errcode(db), sqlite3_system_errno(db));
}

StorageError::StorageError(const std::string& what, int sqlite_code, int system_errno)
    : std::runtime_error(what), sqlite_code_(sqlite_code), system_errno_(system_errno) {}

StorageError::Kind StorageError::kind() const {
  switch (sqlite_code_ & 0xff) {
    case SQLITE_FULL:
      return Kind::kDiskFull;
    case SQLITE_IOERR:
      // A write that found no room can surface as an I/O error (growing the
      // shared-memory index, say): it is a full disk all the same.
      return system_errno_ == ENOSPC || system_errno_ == EDQUOT ? Kind::kDiskFull : Kind::kIoError;
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return Kind::kLocked;
    default:
      return Kind::kOther;
  }
}

std::string StorageError::reason() const { return sqlite_code_ == 0 ? std::string() : sqlite3_errstr(sqlite_code_); }

}  // namespace bosfuse::storage
