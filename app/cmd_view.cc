// bosfuse view: the live page over a run folder (view/live_server.h),
// while a logger records into it or after it finished. Prints the URL on
// stdout and serves until Ctrl-C.

#include <chrono>
#include <iostream>
#include <optional>
#include <thread>

#include "app/command.h"
#include "app/run_control.h"
#include "storage/database.h"
#include "view/live_server.h"

namespace bosfuse::app {
namespace {

struct ViewArgs {
  std::string run;
  std::string listen = "127.0.0.1:8080";
};

void view_run(const ViewArgs& args) {
  view::ViewOptions options;
  view::parse_listen_address(args.listen, options);
  std::atomic<bool>& stop = stop_requested_by_signal();
  std::optional<view::LiveServer> opened;
  try {
    opened.emplace(args.run, options);
  } catch (const storage::StorageError& e) {
    throw std::runtime_error("cannot view '" + args.run + "': it is not a readable bosfuse run (" + e.what() + ")");
  }
  view::LiveServer& server = *opened;
  server.listen();
  std::thread serving([&server] { server.serve(); });
  std::cout << server.url() << std::endl;  // flushed: a script may wait for it
  if (options.host != "127.0.0.1" && options.host != "::1" && options.host != "localhost") {
    std::cerr << "warning: listening on " << options.host
              << ", not loopback: anyone who can reach this host can read the run\n";
  }
  std::cerr << "serving " << args.run << " read-only; Ctrl-C stops\n";
  while (!stop) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  server.stop();
  serving.join();
}

void add_view(CLI::App& root) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* cmd = root.add_subcommand(
      "view", "Serve a live web page of a run (curves, devices, events, frames) while it is recorded or after");
  cmd->add_option("run", args->run, "Run folder")->required();
  cmd->add_option("--listen", args->listen, "HOST:PORT to serve on; loopback unless you say otherwise")
      ->capture_default_str();
  cmd->callback([args] { view_run(*args); });
}

BOSFUSE_COMMAND(add_view);

}  // namespace
}  // namespace bosfuse::app
