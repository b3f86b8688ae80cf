#pragma once
// A Statement is one prepared SQL statement of a Database
// (storage/database.h), in the style of SQLiteCpp: prepared once, then bound
// and stepped as often as needed, the sqlite3_stmt* finalized by its
// unique_ptr's deleter. Use it inside storage/ for every query that takes
// values or returns rows; failures throw StorageError.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

struct sqlite3;
struct sqlite3_stmt;

namespace bosfuse::storage {

struct StatementFinalizer {
  void operator()(sqlite3_stmt* stmt) const noexcept;
};

// bind() indices start at 1 as in SQLite; step()
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

}  // namespace bosfuse::storage
