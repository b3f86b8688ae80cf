// What a storage failure says about itself: a full disk, an I/O error and a
// lock held too long are told apart by SQLite's result code, so the writer
// can count them rather than throw them; and a wait for another
// connection's lock can be cut short from another thread.

#include "storage/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cerrno>
#include <future>
#include <thread>

#include "tests/support/temp_dir.h"

namespace bosfuse::storage {
namespace {

using namespace std::chrono_literals;
using Kind = StorageError::Kind;

TEST(StorageError, ItsKindComesFromSqlitesResultCode) {
  EXPECT_EQ(StorageError("x", SQLITE_FULL).kind(), Kind::kDiskFull);
  EXPECT_EQ(StorageError("x", SQLITE_IOERR_WRITE).kind(), Kind::kIoError);
  EXPECT_EQ(StorageError("x", SQLITE_IOERR_SHMSIZE, ENOSPC).kind(), Kind::kDiskFull) << "no room is a full disk";
  EXPECT_EQ(StorageError("x", SQLITE_BUSY).kind(), Kind::kLocked);
  EXPECT_EQ(StorageError("x", SQLITE_BUSY_SNAPSHOT).kind(), Kind::kLocked);
  EXPECT_EQ(StorageError("x", SQLITE_LOCKED).kind(), Kind::kLocked);
  EXPECT_EQ(StorageError("x", SQLITE_CONSTRAINT_FOREIGNKEY).kind(), Kind::kOther);
  EXPECT_EQ(StorageError("no SQLite here").kind(), Kind::kOther);
  EXPECT_EQ(StorageError("x", SQLITE_FULL).reason(), "database or disk is full");
  EXPECT_EQ(StorageError("no SQLite here").reason(), "");
}

// A database that may not grow fails as a full disk does, with SQLite's code.
TEST(Database, AStoreThatCannotGrowFailsAsAFullDisk) {
  testing::TempDir dir;
  Database db((dir / "full.sqlite").string(), Database::Mode::kCreate);
  db.execute("CREATE TABLE t (x BLOB)");
  db.execute("PRAGMA max_page_count = 3");
  try {
    db.execute("INSERT INTO t VALUES (zeroblob(100000))");
    FAIL() << "the insert did not fail";
  } catch (const StorageError& e) {
    EXPECT_EQ(e.kind(), Kind::kDiskFull) << e.what();
    EXPECT_EQ(e.reason(), "database or disk is full");
  }
  auto insert = db.prepare("INSERT INTO t VALUES (zeroblob(100000))");
  try {
    insert.run();
    FAIL() << "the insert did not fail";
  } catch (const StorageError& e) {
    EXPECT_EQ(e.kind(), Kind::kDiskFull) << e.what();
  }
}

TEST(Database, ALockHeldPastTheTimeoutIsSaidAsSuch) {
  testing::TempDir dir;
  const std::string path = (dir / "locked.sqlite").string();
  Database db(path, Database::Mode::kCreate);
  Database other(path, Database::Mode::kReadWrite);
  other.execute("BEGIN IMMEDIATE");
  db.give_up_lock_waits_at(std::chrono::steady_clock::now() + 200ms);
  const auto start = std::chrono::steady_clock::now();
  try {
    db.execute("BEGIN IMMEDIATE");
    FAIL() << "the lock was taken while another connection held it";
  } catch (const StorageError& e) {
    EXPECT_EQ(e.kind(), Kind::kLocked) << e.what();
  }
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, 150ms) << "it did not wait for the lock";
  EXPECT_LT(waited, 2s) << "it waited past the deadline";
  other.execute("COMMIT");
}

// The stop's thread cuts short a wait the writer's thread is in.
TEST(Database, AWaitForALockEndsWhenAnotherThreadSetsADeadline) {
  testing::TempDir dir;
  const std::string path = (dir / "locked.sqlite").string();
  Database db(path, Database::Mode::kCreate);
  Database other(path, Database::Mode::kReadWrite);
  other.execute("BEGIN IMMEDIATE");
  const auto start = std::chrono::steady_clock::now();
  auto waiting = std::async(std::launch::async, [&] {
    try {
      db.execute("BEGIN IMMEDIATE");
      return Kind::kOther;
    } catch (const StorageError& e) {
      return e.kind();
    }
  });
  std::this_thread::sleep_for(300ms);  // within the 5 s timeout
  db.give_up_lock_waits_at(std::chrono::steady_clock::now());
  EXPECT_EQ(waiting.get(), Kind::kLocked);
  EXPECT_LT(std::chrono::steady_clock::now() - start, Database::kLockTimeout - 2s) << "the deadline was not heeded";
  other.execute("COMMIT");
  db.give_up_lock_waits_at(std::chrono::steady_clock::time_point::max());
  db.execute("BEGIN IMMEDIATE");  // with no deadline and no other holder, the lock is had again
  db.execute("COMMIT");
}

}  // namespace
}  // namespace bosfuse::storage
