#include "storage/transaction.h"

#include <sqlite3.h>

#include "storage/database.h"

namespace bosfuse::storage {

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
