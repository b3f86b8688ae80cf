// `bosfuse cameras`: the GenICam (GigE Vision, USB3 Vision) cameras Aravis
// reaches, with the id an experiment file's `device` takes and the pixel
// formats each offers. Data on stdout; a camera that could not be opened is
// listed with the reason.

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <iostream>
#include <memory>

#include "acquisition/cameras/genicam_cameras.h"
#include "app/command.h"

namespace bosfuse::app {
namespace {

void print_genicam_cameras(const std::vector<std::string>& addresses, bool discover) {
  const auto cameras = acquisition::list_genicam_cameras(addresses, discover);
  if (cameras.empty()) {
    std::cerr << "no GenICam camera found (discovery does not reach loopback: name a camera with --address)\n";
    return;
  }
  for (const auto& c : cameras) {
    std::cout << fmt::format("{}\n  vendor {}, model {}, serial {}, {} at {}\n", c.id.empty() ? c.address : c.id,
                             c.vendor, c.model, c.serial, c.protocol, c.address);
    if (c.problem.empty()) {
      std::cout << fmt::format("  pixel formats: {}\n", fmt::join(c.pixel_formats, ", "));
    } else {
      std::cout << fmt::format("  could not be opened: {}\n", c.problem);
    }
  }
}

void add_cameras(CLI::App& root) {
  auto addresses = std::make_shared<std::vector<std::string>>();
  auto no_discovery = std::make_shared<bool>(false);
  CLI::App* cmd = root.add_subcommand(
      "cameras", "List the GenICam cameras (GigE Vision, USB3 Vision) Aravis finds, with their ids and pixel formats");
  cmd->add_option("--address", *addresses,
                  "Also a camera at this IP address (repeatable); discovery by broadcast does not reach 127.0.0.1");
  cmd->add_flag("--no-discovery", *no_discovery, "Only the cameras named by --address");
  cmd->callback([addresses, no_discovery] { print_genicam_cameras(*addresses, !*no_discovery); });
}

BOSFUSE_COMMAND(add_cameras);

}  // namespace
}  // namespace bosfuse::app
