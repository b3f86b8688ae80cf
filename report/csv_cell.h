#pragma once
// A CSV cell holding text: a channel name, a series name, a fit's message —
// anything a user or a device chose. Every CSV bosfuse writes puts its text
// through here. The cell is quoted when it holds a comma, quote or line break
// (RFC 4180), and neutralised when a spreadsheet would run it as a formula
// (OWASP "CSV injection": a leading =, +, -, @, tab or carriage return): it
// then gets a leading single quote, which spreadsheets show as text, and is
// quoted. Numbers are not text: write them as numbers, so -3.5 stays -3.5.
// A leading single quote is itself doubled, so csv_text_from_cell() gives
// back exactly the text that was written.

#include <string>
#include <string_view>

namespace bosfuse::report {

// The cell to write for `text`, quoted and neutralised as needed.
std::string csv_text_cell(std::string_view text);

// The text a cell held, from the cell's value once a CSV reader has removed
// the quoting: drops the single quote csv_text_cell() put in front.
std::string csv_text_from_cell(std::string_view value);

}  // namespace bosfuse::report
