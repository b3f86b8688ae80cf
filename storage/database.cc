#include "storage/database.h"

#include <sqlite3.h>

#include <algorithm>
#include <string>

#include "storage/sqlite_failure.h"

namespace bosfuse::storage {
namespace {

int open_flags(Database::Mode mode) {
  switch (mode) {
    case Database::Mode::kReadOnly:
      return SQLITE_OPEN_READONLY;
    case Database::Mode::kReadWrite:
      return SQLITE_OPEN_READWRITE;
    case Database::Mode::kCreate:
      return SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    case Database::Mode::kImmutable:
      return SQLITE_OPEN_READONLY | SQLITE_OPEN_URI;
  }
  return SQLITE_OPEN_READONLY;
}

// The file as an SQLite URI with immutable=1 (no locking, no -wal/-shm);
// '?', '#' and '%' in the path are percent-encoded.
std::string immutable_uri(const std::string& path) {
  std::string uri = "file:";
  for (const char c : path) {
    if (c == '?' || c == '#' || c == '%') {
      static constexpr char kHex[] = "0123456789ABCDEF";
      uri += '%';
      uri += kHex[(static_cast<unsigned char>(c) >> 4) & 0xF];
      uri += kHex[static_cast<unsigned char>(c) & 0xF];
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

}  // namespace

void SqliteCloser::operator()(sqlite3* db) const noexcept { sqlite3_close_v2(db); }

// SQLite's busy handler: short sleeps (at most 10 ms, so a lock released is
// taken at once) until the timeout or the deadline, whichever comes first.
int Database::wait_for_lock(void* lock_wait, int attempts) {
  auto& wait = *static_cast<LockWait*>(lock_wait);
  const auto now = std::chrono::steady_clock::now();
  if (attempts == 0) wait.started = now;
  const auto give_up_at = std::chrono::steady_clock::time_point(std::chrono::steady_clock::duration(wait.give_up_at.load()));
  if (now - wait.started >= wait.timeout || now >= give_up_at) return 0;
  sqlite3_sleep(std::min(attempts + 1, 10));
  return 1;
}

void Database::give_up_lock_waits_at(std::chrono::steady_clock::time_point deadline) {
  lock_wait_->give_up_at.store(deadline.time_since_epoch().count());
}

Database::Database(const std::string& path, Mode mode) : path_(path) {
  sqlite3* raw = nullptr;
  // Serialized mode: a connection shared by mistake between threads is slower,
  // never corrupted.
  const std::string name = mode == Mode::kImmutable ? immutable_uri(path) : path;
  const int rc = sqlite3_open_v2(name.c_str(), &raw, open_flags(mode) | SQLITE_OPEN_FULLMUTEX, nullptr);
  db_.reset(raw);  // owned even on failure: sqlite3_open_v2 may allocate a handle
  if (rc != SQLITE_OK) throw_last_error(raw, "cannot open run store '" + path + "'");
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_handler(raw, &Database::wait_for_lock, lock_wait_.get());
  execute("PRAGMA foreign_keys = ON");
  if (mode == Mode::kReadWrite || mode == Mode::kCreate) {
    execute("PRAGMA journal_mode = WAL");
    // NORMAL is durable in WAL mode except for the last transactions on power
    // loss; the database itself is never corrupted.
    execute("PRAGMA synchronous = NORMAL");
  }
}

void Database::execute(std::string_view sql) {
  char* message = nullptr;
  const std::string text(sql);
  if (sqlite3_exec(db_.get(), text.c_str(), nullptr, nullptr, &message) != SQLITE_OK) {
    std::string reason = message ? message : "unknown error";
    sqlite3_free(message);
    throw StorageError("SQL failed (" + text.substr(0, 80) + "): " + reason, sqlite3_extended_errcode(db_.get()),
                       sqlite3_system_errno(db_.get()));
  }
}

Statement Database::prepare(std::string_view sql) { return Statement(db_.get(), sql); }

std::int64_t Database::last_insert_rowid() const { return sqlite3_last_insert_rowid(db_.get()); }

}  // namespace bosfuse::storage
