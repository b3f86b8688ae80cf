#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <iostream>

#include "app/argument_check.h"
#include "app/command.h"
#include "app/run_control.h"
#include "pipeline/available_memory.h"
#include "pipeline/simd_environment.h"

namespace bosfuse::app {

std::vector<std::pair<std::string, CommandAdder>>& command_registry() {
  static std::vector<std::pair<std::string, CommandAdder>> registry;
  return registry;
}

namespace {

// Data goes to standard output, so `bosfuse export RUN --csv > f.csv` holds
// only data: every message, from info to error, goes to standard error.
void log_to_stderr() {
  spdlog::set_default_logger(
      std::make_shared<spdlog::logger>("", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
}

}  // namespace
}  // namespace bosfuse::app

int main(int argc, char** argv) {
  using namespace bosfuse::app;
  log_to_stderr();
  // What the host sets for fusion's evaluations, which read no environment.
  bosfuse::pipeline::apply_simd_environment();
  bosfuse::pipeline::install_memory_probe();
  CLI::App root{
      "bosfuse: thermocouple-and-image data fusion logger for background oriented "
      "schlieren (BOS) convection experiments"};
  root.set_version_flag("--version", "bosfuse 0.1.0");
  root.require_subcommand(1);
  root.fallthrough();
  // Before any subcommand runs: the options of the root are parsed first.
  root.add_flag_callback(
      "-q,--quiet", [] { spdlog::set_level(spdlog::level::warn); }, "Only warnings and errors (on standard error)");
  root.add_flag_callback(
      "-v,--verbose", [] { spdlog::set_level(spdlog::level::debug); }, "Say more of what is done (on standard error)");
  auto& commands = command_registry();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [name, add] : commands) add(root);
  try {
    if (const auto unknown = unknown_argument(root, argc, argv)) {
      spdlog::error("{}", *unknown);
      return static_cast<int>(CLI::ExitCodes::ExtrasError);
    }
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return root.exit(e);
  } catch (const CommandFailure& e) {
    spdlog::error("{}", e.what());
    return e.status();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kExitFailure;
  }
  return EXIT_SUCCESS;
}
