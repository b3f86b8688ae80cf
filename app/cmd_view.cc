// bosfuse view: the live page over a run folder (view/live_server.h),
// while a logger records into it or after it finished. Prints the URL on
// stdout and serves until Ctrl-C.

#include <chrono>
#include <iostream>
#include <thread>

#include "app/command.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "app/served_view.h"

namespace bosfuse::app {
namespace {

struct ViewArgs {
  std::string run;
  std::string listen = kDefaultListen;
  bool token = false;
};

void view_run(const ViewArgs& args) {
  std::atomic<bool>& stop = stop_requested_by_signal();
  const ServedView served(args.run, args.listen, args.token);
  std::cout << served.url() << std::endl;  // flushed: a script may wait for it
  std::cerr << "serving " << args.run << " read-only; Ctrl-C stops\n";
  while (!stop) std::this_thread::sleep_for(std::chrono::milliseconds(100));
}

void add_view(CLI::App& root) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* cmd = root.add_subcommand(
      "view",
      "Serve a live web page of a run (curves, live BOS temperatures, frames, devices, alarms, events) while it is "
      "recorded or after");
  cmd->add_option("run", args->run, "Run folder")->required()->transform(run_folder_argument());
  cmd->add_option("--listen", args->listen, "HOST:PORT to serve on; loopback unless you say otherwise")
      ->capture_default_str();
  cmd->add_flag("--token", args->token,
                "Want the token of the printed URL on loopback too (a machine others log into); off loopback it "
                "is always wanted");
  cmd->callback([args] { view_run(*args); });
}

BOSFUSE_COMMAND(add_view);

}  // namespace
}  // namespace bosfuse::app
