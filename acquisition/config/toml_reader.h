#pragma once
// TomlReader reads one TOML table of an experiment file with errors a user
// can act on: every message names the file, the line and the full key
// (`experiment.toml:14: devices[1].port: expected an integer`). Keys the
// table does not know are errors too, since a typo in a lab configuration
// silently falling back to a default is worse than refusing to start.

#include <toml++/toml.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace bosfuse::acquisition {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class TomlReader {
 public:
  // `key_path` is the table's own path, e.g. "devices[1]".
  TomlReader(const toml::table& table, std::string key_path, std::string source_name);

  bool has(std::string_view key) const;
  std::string string(std::string_view key) const;
  std::optional<std::string> optional_string(std::string_view key) const;
  std::int64_t integer(std::string_view key) const;
  std::optional<std::int64_t> optional_integer(std::string_view key) const;
  double number(std::string_view key) const;  // integer or float
  std::optional<double> optional_number(std::string_view key) const;
  std::optional<bool> optional_bool(std::string_view key) const;
  // An integer within [low, high]. TOML integers are 64-bit: the range is
  // checked on that value, before anything narrows it, so 4294967296 is
  // refused naming the key instead of being read as 0. Every integer key
  // is read through one of these.
  std::int64_t integer_in(std::string_view key, std::int64_t low, std::int64_t high) const;  // required
  std::optional<std::int64_t> optional_integer_in(std::string_view key, std::int64_t low, std::int64_t high) const;
  // The same, `fallback` when absent, for keys that fit an int.
  int integer_in(std::string_view key, int fallback, int low, int high) const;
  // A finite number within [low, high], `fallback` when absent; `meaning`
  // says what it is in the refusal ("experiment seconds per recorded second").
  double number_in(std::string_view key, double fallback, double low, double high, std::string_view meaning) const;
  // A duration is kept in int64 nanoseconds (±292 years); a year of
  // seconds is more than any period or timeout a run needs.
  static constexpr double kLongestSeconds = 365.25 * 86400;
  // A duration in seconds of at least `minimum_s` and at most
  // kLongestSeconds, `fallback_s` when absent.
  std::chrono::nanoseconds seconds(std::string_view key, double fallback_s, double minimum_s) const;
  // An optional [x, y] pair, e.g. a position in image pixels.
  std::optional<std::pair<double, double>> optional_pair(std::string_view key, const std::string& meaning) const;
  // An array of integers 0-255, e.g. the bytes of a report; empty if absent.
  std::vector<std::uint8_t> bytes(std::string_view key) const;
  // An array of such arrays, e.g. several reports; empty if absent.
  std::vector<std::vector<std::uint8_t>> byte_arrays(std::string_view key) const;
  std::vector<double> numbers(std::string_view key) const;     // an array of numbers; empty if absent
  std::vector<TomlReader> tables(std::string_view key) const;  // an array of tables; empty if absent
  std::optional<TomlReader> table(std::string_view key) const;
  const toml::node* node(std::string_view key) const;

  // An error about `key` (or the table itself when empty) at its line.
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;
  // Where `key` is, as fail() names it ("exp.toml:7: devices[0].host"), for
  // an error found after parsing.
  std::string where(std::string_view key) const;
  // Fails on the first key that was never asked for.
  void reject_unknown_keys() const;

  std::string key_path(std::string_view key) const;

 private:
  const toml::node& require(std::string_view key) const;
  std::vector<std::uint8_t> bytes_of(const toml::node& node, std::string_view key) const;

  const toml::table* table_;
  std::string key_path_;
  std::string source_name_;
  mutable std::set<std::string, std::less<>> used_;
};

// Parses `text`; a syntax error becomes a ConfigError naming the line.
toml::table parse_toml(std::string_view text, const std::string& source_name);

}  // namespace bosfuse::acquisition
