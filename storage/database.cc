#include "storage/database.h"

#include <algorithm>
#include <cerrno>
#include <string>

namespace bosfuse::storage {
namespace {

[[noreturn]] void fail(sqlite3* db, const std::string& what) {
  if (!db) throw StorageError(what + ": out of memory", SQLITE_NOMEM);
  throw StorageError(what + ": " + sqlite3_errmsg(db), sqlite3_extended_errcode(db), sqlite3_system_errno(db));
}

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
  if (rc != SQLITE_OK) fail(raw, "cannot open run store '" + path + "'");
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

Statement::Statement(sqlite3* db, std::string_view sql) : db_(db) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v3(db, sql.data(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT, &raw, nullptr) !=
      SQLITE_OK) {
    fail(db, "cannot prepare SQL (" + std::string(sql.substr(0, 80)) + ")");
  }
  stmt_.reset(raw);
}

void Statement::check(int rc, const char* what) const {
  if (rc != SQLITE_OK) fail(db_, std::string(what) + " in (" + sqlite3_sql(stmt_.get()) + ")");
}

Statement& Statement::bind(int index, std::int64_t value) {
  check(sqlite3_bind_int64(stmt_.get(), index, value), "bind");
  return *this;
}
Statement& Statement::bind(int index, double value) {
  check(sqlite3_bind_double(stmt_.get(), index, value), "bind");
  return *this;
}
Statement& Statement::bind(int index, std::string_view value) {
  check(sqlite3_bind_text(stmt_.get(), index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT), "bind");
  return *this;
}
Statement& Statement::bind(int index, std::nullopt_t) {
  check(sqlite3_bind_null(stmt_.get(), index), "bind");
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(stmt_.get());
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const std::string sql = sqlite3_sql(stmt_.get());
  sqlite3_reset(stmt_.get());
  fail(db_, "SQL step failed in (" + sql + ")");
}

void Statement::run() {
  step();
  reset();
}

void Statement::reset() { sqlite3_reset(stmt_.get()); }

bool Statement::is_null(int column) const { return sqlite3_column_type(stmt_.get(), column) == SQLITE_NULL; }
std::int64_t Statement::column_int64(int column) const { return sqlite3_column_int64(stmt_.get(), column); }
double Statement::column_double(int column) const { return sqlite3_column_double(stmt_.get(), column); }
std::string Statement::column_text(int column) const {
  const auto* text = sqlite3_column_text(stmt_.get(), column);
  return text ? reinterpret_cast<const char*>(text) : std::string();
}
std::optional<double> Statement::column_optional_double(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_double(column);
}
std::optional<std::int64_t> Statement::column_optional_int64(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_int64(column);
}
std::optional<std::string> Statement::column_optional_text(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_text(column);
}

Transaction::Transaction(Database& db) : db_(db) { db_.execute("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (committed_) return;
  // Destructors never throw: a failed rollback leaves SQLite to roll back the
  // open transaction when the connection closes.
  sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  db_.execute("COMMIT");
  committed_ = true;
}

}  // namespace bosfuse::storage
