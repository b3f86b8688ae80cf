#pragma once
// A look at the command line before CLI11 parses it, so a typo is named
// where it is made: `sim modbsu` names the unknown subcommand of `sim`
// (CLI11 would say "A subcommand is required"), `process --windw 32` names
// the option and suggests `--window`. Each suggestion is the nearest known
// name by edit distance, when one is near enough to be meant.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace CLI {
class App;
}

namespace bosfuse::app {

// Levenshtein distance: insertions, deletions and substitutions.
std::size_t edit_distance(std::string_view a, std::string_view b);

// The candidate nearest to `word`, if within a third of its length (at
// least 2 edits); nothing when none is that near.
std::optional<std::string> nearest_name(std::string_view word, const std::vector<std::string>& candidates);

// The message for the first unknown subcommand or long option in argv, or
// nothing when every one is known. Values of options are skipped.
std::optional<std::string> unknown_argument(const CLI::App& root, int argc, const char* const* argv);

}  // namespace bosfuse::app
