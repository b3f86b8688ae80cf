// bosfuse replay: record a recorded run again through the real device paths.

#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>

#include "app/command.h"
#include "app/output_stream.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "pipeline/processing_settings.h"
#include "sim/replay_session.h"

namespace bosfuse::app {
namespace {

struct ReplayArgs {
  std::string run;
  std::string out;
  double speed = 1;
};

void replay(const ReplayArgs& args) {
  refuse_standard_output(args.out, "--out", "a run is a folder (run.sqlite, frames/)");
  check_new_run_output(args.out, "--out");  // not the recorded run itself, nor inside its own folders
  sim::ReplaySession session(args.run, args.out, args.speed);
  if (pipeline::inherit_settings(args.run, args.out)) {
    spdlog::info("the recorded run's processing settings are the replay's: `bosfuse process {}` repeats them",
                 args.out);
  }
  const auto summary = session.run(stop_requested_by_signal());
  // The summary on stderr: the replay's product is the run folder.
  std::cerr << summary.BriefReport() << "\nreplayed run: " << session.dir().string() << "\n";
}

void add_replay(CLI::App& root) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = root.add_subcommand(
      "replay", "Record a recorded run again through simulated devices (Modbus on loopback, a replayed camera)");
  cmd->add_option("run", args->run, "Recorded run folder")->required()->transform(run_folder_argument());
  cmd->add_option("--out,-o", args->out, "New run folder to create")->required();
  cmd->add_option("--speed", args->speed,
                  "Replay N times faster than recorded (the new run's time scale is the "
                  "recorded run's times N)")
      ->check(CLI::Range(0.01, 10000.0))
      ->capture_default_str();
  cmd->callback([args] { replay(*args); });
}

BOSFUSE_COMMAND(add_replay);

}  // namespace
}  // namespace bosfuse::app
