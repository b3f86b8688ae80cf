#include <spdlog/spdlog.h>

#include <cstdlib>
#include <exception>

#include "app/command.h"
#include "app/run_control.h"

namespace bosfuse::app {

std::vector<CommandAdder>& command_registry() {
  static std::vector<CommandAdder> registry;
  return registry;
}

}  // namespace bosfuse::app

int main(int argc, char** argv) {
  CLI::App root{
      "bosfuse: thermocouple-and-image data fusion logger for background oriented "
      "schlieren (BOS) convection experiments"};
  root.set_version_flag("--version", "bosfuse 0.1.0");
  root.require_subcommand(1);
  root.fallthrough();
  for (const auto& add : bosfuse::app::command_registry()) add(root);
  try {
    root.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return root.exit(e);
  } catch (const bosfuse::app::CommandFailure& e) {
    spdlog::error("{}", e.what());
    return e.status();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
