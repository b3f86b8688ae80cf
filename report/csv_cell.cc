#include "report/csv_cell.h"

namespace bosfuse::report {
namespace {

// What a spreadsheet takes for the start of a formula, plus the single quote
// that marks a neutralised cell (so that one is never ambiguous).
bool needs_prefix(std::string_view text) {
  return !text.empty() && std::string_view("=+-@\t\r'").find(text.front()) != std::string_view::npos;
}

}  // namespace

std::string csv_text_cell(std::string_view text) {
  const bool prefixed = needs_prefix(text);
  if (!prefixed && text.find_first_of(",\"\n\r") == std::string_view::npos) return std::string(text);
  std::string out = prefixed ? "\"'" : "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

std::string csv_text_from_cell(std::string_view value) {
  if (value.size() >= 2 && value.front() == '\'' && needs_prefix(value.substr(1))) value.remove_prefix(1);
  return std::string(value);
}

}  // namespace bosfuse::report
