// bosfuse mark: records a marker event in a run, now — typically "heater
// off" while the logger records it, so the run's declared origin ([run]
// origin = "heater off") is the moment it happened. Every command then
// counts experiment time from it (storage/experiment_clock.h).

#include <iostream>

#include "acquisition/clock.h"
#include "app/command.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct MarkArgs {
  std::string run;
  std::string message;
};

void mark(const MarkArgs& args) {
  if (args.message.empty()) throw std::runtime_error("a marker needs a name, e.g. \"heater off\"");
  auto store = storage::RunStore::open(args.run, true);
  const storage::Event marker{0, std::nullopt, acquisition::utc_now_ns(), "marker", args.message};
  store.write_events({&marker, 1});
  std::cout << "marked \"" << args.message << "\" at " << storage::format_iso8601_utc(marker.t_ns, 3) << " in "
            << args.run << "\n";
  const auto origin = store.run().origin_event;
  if (origin == args.message && store.marker_ns(args.message) == marker.t_ns) {
    std::cerr << "this is the run's declared origin: experiment time now counts from it\n";
  }
}

void add_mark(CLI::App& root) {
  auto args = std::make_shared<MarkArgs>();
  CLI::App* cmd = root.add_subcommand(
      "mark", "Record a marker event (e.g. \"heater off\") in a run now, also while a logger records it");
  cmd->add_option("run", args->run, "Run folder")->required();
  cmd->add_option("message", args->message, "What happened; the run's [run] origin names the marker that is t = 0")
      ->required();
  cmd->callback([args] { mark(*args); });
}

BOSFUSE_COMMAND(add_mark);

}  // namespace
}  // namespace bosfuse::app
