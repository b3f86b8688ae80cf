// bosfuse acquire: log the devices of an experiment file into a run folder.

#include <spdlog/spdlog.h>

#include <iostream>

#include "acquisition/clock.h"
#include "acquisition/config/experiment_config.h"
#include "acquisition/logger.h"
#include "app/command.h"
#include "app/output_stream.h"
#include "app/run_control.h"
#include "app/served_view.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

struct AcquireArgs {
  std::string experiment;
  std::string out;
  std::string duration;
  bool append = false;
  std::string live;  // --live HOST:PORT; empty: no live page
};

// A run that looks fine but lacks a device's data: said at the end, where a
// user (or a script, by the exit status) cannot miss it.
std::string what_is_missing(const acquisition::Logger::Summary& summary) {
  std::string missing;
  const auto add = [&](const std::string& what) { missing += (missing.empty() ? "" : "; ") + what; };
  for (const auto& device : summary.devices) {
    if (device.stats.polls_ok == 0) add("device " + device.name + " delivered no readings");
  }
  for (const auto& camera : summary.cameras) {
    if (camera.stats.frames == 0) {
      add("camera " + camera.name + " delivered no frames");
    } else if (camera.stats.failures > 0) {
      add("camera " + camera.name + " lost " + std::to_string(camera.stats.failures) + " frames");
    }
  }
  return missing;
}

// The exit message of a run the store could not take whole.
std::string what_was_lost(const storage::RunWriter::Stats& writer) {
  std::string message;
  if (writer.lost() > 0) {
    message = std::to_string(writer.lost()) + " records read were not stored: " + writer.last_error;
  }
  if (writer.status_written) return message + "; the run is marked interrupted";
  return message + (message.empty() ? "" : "; ") +
         "the run's status could not be written; the next command that opens it marks it interrupted";
}

void acquire(const AcquireArgs& args) {
  refuse_standard_output(args.out, "--out", "a run is a folder (run.sqlite, frames/)");
  if (!args.append) check_new_run_output(args.out, "--out");  // a new run lands on no run's own files
  const auto config = acquisition::load_experiment(args.experiment);
  if (config.device_count() == 0) throw std::runtime_error(args.experiment + ": no [[devices]] to log");
  // Everything that can refuse the start does so before the run exists, so
  // a refused start leaves no empty interrupted run behind.
  acquisition::check_hosts_resolve(config);
  acquisition::check_replayed_runs(config);
  acquisition::check_genicam_cameras(config, [](const std::string& line) { spdlog::warn("{}", line); });
  acquisition::check_free_space(config, args.out);
  acquisition::LoggerOptions options;
  options.disk.min_free_bytes = static_cast<std::uint64_t>(config.min_free_mb) << 20;
  if (!args.duration.empty()) options.duration = parse_duration(args.duration);
  options.on_progress = [](const std::string& line) { spdlog::info("{}", line); };
  options.on_alarm = [](const std::string& line) { spdlog::warn("{}", line); };
  const storage::RunInfo info = acquisition::run_info(config, acquisition::utc_now_ns());
  auto store = storage::RunStore::create(
      args.out, info, args.append ? storage::RunStore::CreateMode::kAppend : storage::RunStore::CreateMode::kNew);
  if (options.duration) store.set_planned_end(info.started_ns + options.duration->count());
  acquisition::Logger logger(store, options);
  logger.add_devices(config);
  const auto live = start_live_view(args.out, args.live);
  spdlog::info("logging {} devices into {} ({})", config.device_count(), args.out,
               args.duration.empty() ? "until Ctrl-C" : "for " + args.duration);
  const auto summary = logger.run(stop_requested_by_signal());
  // A summary for the person watching, on stderr: acquire's product is the
  // run folder, and its standard output stays empty (data only).
  std::cerr << summary.BriefReport() << "\nrun store: " << (store.dir() / storage::RunStore::kDatabaseFileName).string()
            << std::endl;
  if (!summary.complete()) throw CommandFailure(kExitIncompleteRun, what_was_lost(summary.writer));
  if (const std::string missing = what_is_missing(summary); !missing.empty()) {
    throw CommandFailure(kExitDeviceSilent, "the run is recorded, but " + missing);
  }
}

void add_acquire(CLI::App& root) {
  auto args = std::make_shared<AcquireArgs>();
  CLI::App* cmd = root.add_subcommand("acquire", "Log the devices of an experiment file into a run folder");
  cmd->add_option("experiment", args->experiment, "Experiment TOML file")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out,-o", args->out, "Run folder to create")->required();
  cmd->add_option("--duration", args->duration, "Stop after this long (30s, 10m, 2h); default: until Ctrl-C");
  cmd->add_flag("--append", args->append, "Continue the run already in the folder instead of refusing it");
  add_live_option(*cmd, args->live);
  cmd->callback([args] { acquire(*args); });
}

BOSFUSE_COMMAND(add_acquire);

}  // namespace
}  // namespace bosfuse::app
