#pragma once
// The bosfuse command line is a set of subcommands, each thin glue over the
// libraries. A subcommand lives in its own app/cmd_*.cc file and registers
// itself at start-up with BOSFUSE_COMMAND, so adding one touches no other
// file. Subcommands are listed in the order of their adders' names, not in
// the order the program's static initialisation happens to run. A
// subcommand's callback throws std::exception on failure; main()
// prints the message and exits non-zero.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace bosfuse::app {

using CommandAdder = std::function<void(CLI::App& root)>;

// Each adder under its name ("add_acquire"), in registration order.
std::vector<std::pair<std::string, CommandAdder>>& command_registry();

struct CommandRegistrar {
  CommandRegistrar(std::string name, CommandAdder adder) {
    command_registry().emplace_back(std::move(name), std::move(adder));
  }
};

}  // namespace bosfuse::app

#define BOSFUSE_COMMAND_CONCAT2(a, b) a##b
#define BOSFUSE_COMMAND_CONCAT(a, b) BOSFUSE_COMMAND_CONCAT2(a, b)
#define BOSFUSE_COMMAND(adder) \
  static const ::bosfuse::app::CommandRegistrar BOSFUSE_COMMAND_CONCAT(bosfuse_command_registrar_, __COUNTER__) { #adder, adder }
