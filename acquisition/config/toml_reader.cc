#include "acquisition/config/toml_reader.h"

#include <cmath>
#include <sstream>

namespace bosfuse::acquisition {
namespace {

std::string location(const std::string& source, const toml::source_region& region) {
  return source + ":" + std::to_string(region.begin.line);
}

std::optional<double> as_number(const toml::node& node) {
  if (auto v = node.value<double>(); v && (node.is_floating_point() || node.is_integer())) return *v;
  return std::nullopt;
}

}  // namespace

TomlReader::TomlReader(const toml::table& table, std::string key_path, std::string source_name)
    : table_(&table), key_path_(std::move(key_path)), source_name_(std::move(source_name)) {}

std::string TomlReader::key_path(std::string_view key) const {
  if (key_path_.empty()) return std::string(key);
  if (key.empty()) return key_path_;
  return key_path_ + "." + std::string(key);
}

void TomlReader::fail(std::string_view key, const std::string& message) const {
  throw ConfigError(where(key) + ": " + message);
}

std::string TomlReader::where(std::string_view key) const {
  const toml::node* at = key.empty() ? nullptr : table_->get(key);
  const toml::source_region& region = at ? at->source() : table_->source();
  return location(source_name_, region) + ": " + key_path(key);
}

const toml::node* TomlReader::node(std::string_view key) const {
  used_.emplace(key);
  return table_->get(key);
}

bool TomlReader::has(std::string_view key) const { return table_->contains(key); }

const toml::node& TomlReader::require(std::string_view key) const {
  const toml::node* found = node(key);
  if (!found) fail("", "missing required key '" + std::string(key) + "'");
  return *found;
}

std::string TomlReader::string(std::string_view key) const {
  const auto value = require(key).value<std::string>();
  if (!value || !require(key).is_string()) fail(key, "expected a string");
  return *value;
}

std::optional<std::string> TomlReader::optional_string(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return string(key);
}

std::int64_t TomlReader::integer(std::string_view key) const {
  const toml::node& n = require(key);
  if (!n.is_integer()) fail(key, "expected an integer");
  return *n.value<std::int64_t>();
}

std::optional<std::int64_t> TomlReader::optional_integer(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return integer(key);
}

double TomlReader::number(std::string_view key) const {
  const auto value = as_number(require(key));
  if (!value) fail(key, "expected a number");
  if (!std::isfinite(*value)) fail(key, "expected a finite number");
  return *value;
}

std::optional<double> TomlReader::optional_number(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  return number(key);
}

std::optional<bool> TomlReader::optional_bool(std::string_view key) const {
  if (!has(key)) return std::nullopt;
  const toml::node& n = require(key);
  if (!n.is_boolean()) fail(key, "expected true or false");
  return *n.value<bool>();
}

std::optional<std::int64_t> TomlReader::optional_integer_in(std::string_view key, std::int64_t low,
                                                            std::int64_t high) const {
  const std::optional<std::int64_t> value = optional_integer(key);
  if (value && (*value < low || *value > high)) {
    fail(key, "must be between " + std::to_string(low) + " and " + std::to_string(high));
  }
  return value;
}

std::int64_t TomlReader::integer_in(std::string_view key, std::int64_t low, std::int64_t high) const {
  require(key);
  return *optional_integer_in(key, low, high);
}

int TomlReader::integer_in(std::string_view key, int fallback, int low, int high) const {
  return static_cast<int>(optional_integer_in(key, low, high).value_or(fallback));
}

double TomlReader::number_in(std::string_view key, double fallback, double low, double high,
                             std::string_view meaning) const {
  const double value = optional_number(key).value_or(fallback);
  if (!(value >= low && value <= high)) {
    std::ostringstream text;
    text << "expected " << meaning << " from " << low << " to " << high << ", not " << value;
    fail(key, text.str());
  }
  return value;
}

std::chrono::nanoseconds TomlReader::seconds(std::string_view key, double fallback_s, double minimum_s) const {
  const double value = optional_number(key).value_or(fallback_s);
  if (!std::isfinite(value) || value < minimum_s || value > kLongestSeconds) {
    std::ostringstream text;
    text << "must be a number of seconds from " << minimum_s << " to " << kLongestSeconds;
    fail(key, text.str());
  }
  return std::chrono::nanoseconds(static_cast<std::int64_t>(std::llround(value * 1e9)));
}

std::optional<std::pair<double, double>> TomlReader::optional_pair(std::string_view key,
                                                                   const std::string& meaning) const {
  const std::vector<double> values = numbers(key);
  if (values.empty() && !has(key)) return std::nullopt;
  if (values.size() != 2) fail(key, "expected " + meaning);
  return std::pair(values[0], values[1]);
}

std::vector<std::uint8_t> TomlReader::bytes(std::string_view key) const {
  const toml::node* n = node(key);
  return n ? bytes_of(*n, key) : std::vector<std::uint8_t>{};
}

std::vector<std::vector<std::uint8_t>> TomlReader::byte_arrays(std::string_view key) const {
  const toml::node* n = node(key);
  if (!n) return {};
  const toml::array* array = n->as_array();
  if (!array) fail(key, "expected an array of byte arrays, e.g. [[0x49, 0, 0x10, 1]]");
  std::vector<std::vector<std::uint8_t>> out;
  for (const toml::node& element : *array) out.push_back(bytes_of(element, key));
  return out;
}

std::vector<std::uint8_t> TomlReader::bytes_of(const toml::node& n, std::string_view key) const {
  const toml::array* array = n.as_array();
  if (!array) fail(key, "expected an array of bytes, e.g. [0x18, 0x00]");
  std::vector<std::uint8_t> out;
  for (const toml::node& element : *array) {
    const auto value = element.value<std::int64_t>();
    if (!element.is_integer() || *value < 0 || *value > 255) fail(key, "expected integers 0-255 (bytes)");
    out.push_back(static_cast<std::uint8_t>(*value));
  }
  return out;
}

std::vector<double> TomlReader::numbers(std::string_view key) const {
  const toml::node* n = node(key);
  if (!n) return {};
  const toml::array* array = n->as_array();
  if (!array) fail(key, "expected an array of numbers");
  std::vector<double> values;
  for (const toml::node& element : *array) {
    const auto value = as_number(element);
    if (!value || !std::isfinite(*value)) fail(key, "expected an array of finite numbers");
    values.push_back(*value);
  }
  return values;
}

std::vector<TomlReader> TomlReader::tables(std::string_view key) const {
  const toml::node* n = node(key);
  if (!n) return {};
  const toml::array* array = n->as_array();
  if (!array || !array->is_array_of_tables()) fail(key, "expected an array of tables ([[" + key_path(key) + "]])");
  std::vector<TomlReader> readers;
  for (std::size_t i = 0; i < array->size(); ++i) {
    readers.emplace_back(*array->get(i)->as_table(), key_path(key) + "[" + std::to_string(i) + "]", source_name_);
  }
  return readers;
}

std::optional<TomlReader> TomlReader::table(std::string_view key) const {
  const toml::node* n = node(key);
  if (!n) return std::nullopt;
  if (!n->is_table()) fail(key, "expected a table");
  return TomlReader(*n->as_table(), key_path(key), source_name_);
}

void TomlReader::reject_unknown_keys() const {
  for (const auto& [key, value] : *table_) {
    if (!used_.contains(key.str())) fail(key.str(), "unknown key (a typo?)");
  }
}

toml::table parse_toml(std::string_view text, const std::string& source_name) {
  try {
    return toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    throw ConfigError(location(source_name, e.source()) + ": " + std::string(e.description()));
  }
}

}  // namespace bosfuse::acquisition
