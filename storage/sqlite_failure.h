#pragma once
// The one way storage/'s SQLite wrappers turn a failed call into a
// StorageError: the connection's last message, extended code and errno.
// Internal to storage/ (database.cc, statement.cc); the rest of bosfuse
// catches StorageError and never sees a connection.

#include <string>

struct sqlite3;

namespace bosfuse::storage {

// Throws StorageError("<what>: <SQLite's message>") for the connection's
// last failure; a null `db` is SQLite's way of saying it had no memory.
[[noreturn]] void throw_last_error(sqlite3* db, const std::string& what);

}  // namespace bosfuse::storage
