#include "app/argument_check.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <numeric>

namespace bosfuse::app {
namespace {

std::string path_of(const CLI::App& app) {
  std::string path = app.get_name();
  for (const CLI::App* parent = app.get_parent(); parent; parent = parent->get_parent()) {
    if (!parent->get_name().empty()) path = parent->get_name() + " " + path;
  }
  return "bosfuse" + (path.empty() ? "" : " " + path);
}

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(sub->get_name());
  return names;
}

const CLI::App* subcommand_named(const CLI::App& app, const std::string& name) {
  const auto found = app.get_subcommands([&](const CLI::App* sub) { return sub->get_name() == name; });
  return found.empty() ? nullptr : found.front();
}

bool has_positionals(const CLI::App& app) {
  const auto options = app.get_options([](const CLI::Option* o) { return o->get_positional(); });
  return !options.empty();
}

// An option of `app` or of an app above it (the root's options fall through).
const CLI::Option* find_option(const CLI::App& app, const std::string& name) {
  for (const CLI::App* a = &app; a; a = a->get_parent()) {
    if (const CLI::Option* option = a->get_option_no_throw(name)) return option;
  }
  return nullptr;
}

std::vector<std::string> long_option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* a = &app; a; a = a->get_parent()) {
    for (const CLI::Option* o : a->get_options()) {
      for (const std::string& name : o->get_lnames()) names.push_back("--" + name);
    }
  }
  return names;
}

std::string unknown_subcommand(const CLI::App& app, std::string_view word) {
  const auto names = subcommand_names(app);
  std::string known;
  for (const auto& name : names) known += (known.empty() ? "" : ", ") + name;
  const std::string of = app.get_parent() ? fmt::format(" of '{}'", path_of(app)) : "";
  const auto near = nearest_name(word, names);
  return fmt::format("unknown subcommand '{}'{} (one of: {}){}", word, of, known,
                     near ? fmt::format("; did you mean '{}'?", *near) : "");
}

bool looks_like_option(std::string_view token) {
  return token.size() > 1 && token[0] == '-' && !(token[1] >= '0' && token[1] <= '9') && token[1] != '.';
}

}  // namespace

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::optional<std::string> nearest_name(std::string_view word, const std::vector<std::string>& candidates) {
  const std::size_t limit = std::max<std::size_t>(2, word.size() / 3);
  std::optional<std::string> best;
  std::size_t best_distance = limit + 1;
  for (const std::string& candidate : candidates) {
    const std::size_t d = edit_distance(word, candidate);
    if (d < best_distance) best_distance = d, best = candidate;
  }
  return best;
}

std::optional<std::string> unknown_argument(const CLI::App& root, int argc, const char* const* argv) {
  const CLI::App* app = &root;
  for (int i = 1; i < argc; ++i) {
    const std::string token = argv[i];
    if (token == "--") break;
    if (token.rfind("--", 0) == 0) {
      const std::string name = token.substr(0, token.find('='));
      const CLI::Option* option = find_option(*app, name);
      if (!option) {
        const auto near = nearest_name(name, long_option_names(*app));
        return fmt::format("unknown option '{}' of '{}'{}", name, path_of(*app),
                           near ? fmt::format("; did you mean '{}'?", *near) : "");
      }
      const bool value_follows = token.find('=') == std::string::npos && option->get_items_expected_max() > 0;
      if (value_follows && i + 1 < argc && !looks_like_option(argv[i + 1])) ++i;
      continue;
    }
    if (looks_like_option(token)) continue;  // short options and their bundles: CLI11 names those
    if (app->get_subcommands([](const CLI::App*) { return true; }).empty()) continue;
    if (const CLI::App* sub = subcommand_named(*app, token)) {
      app = sub;
    } else if (!has_positionals(*app)) {
      return unknown_subcommand(*app, token);
    }
  }
  return std::nullopt;
}

}  // namespace bosfuse::app
