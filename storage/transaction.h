#pragma once
// A Transaction is the RAII guard of one write transaction on a Database
// (storage/database.h), in the style of SQLiteCpp. Use it around every batch
// of writes that must land whole or not at all.

namespace bosfuse::storage {

class Database;

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
