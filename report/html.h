#pragma once
// Small pieces of the self-contained HTML page: numbers as a reader sees
// them, escaping and base64 data URIs.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace bosfuse::report {

// A number for a reader, formatted with `format` (fmt syntax, e.g. "{:.3g}"),
// or "—" when it does not exist (NaN, ±inf): a page never shows "nan".
std::string display_number(double value, std::string_view format);

// &, <, >, " and ' as entities, so any run or channel name is safe in text and attributes.
std::string html_escape(std::string_view text);

// Standard base64 (RFC 4648, with padding).
std::string base64_encode(std::span<const std::uint8_t> bytes);

// "data:<mime>;base64,..." of a file's bytes; throws std::runtime_error if unreadable.
std::string data_uri(const std::filesystem::path& file, std::string_view mime);

// A file-name-safe form of a name: letters, digits, '-' and '_' kept, anything else '_'.
std::string slug(std::string_view name);

}  // namespace bosfuse::report
