// bosfuse replay: record a recorded run again through the real device paths.

#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <thread>

#include "acquisition/clock.h"
#include "acquisition/experiment_config.h"
#include "acquisition/logger.h"
#include "app/command.h"
#include "app/output_stream.h"
#include "app/run_argument.h"
#include "app/run_control.h"
#include "pipeline/processing_settings.h"
#include "sim/replay.h"
#include "storage/run_store.h"

namespace bosfuse::app {
namespace {

using namespace std::chrono_literals;

struct ReplayArgs {
  std::string run;
  std::string out;
  double speed = 1;
};

bool every_sample_served(const sim::RecordedRun& recorded,
                         const std::vector<std::unique_ptr<sim::ModbusSimServer>>& servers) {
  for (std::size_t d = 0; d < servers.size(); ++d) {
    const auto& samples = recorded.devices[d].samples;
    for (std::size_t c = 0; c < samples.size(); ++c) {
      if (servers[d]->draws(static_cast<int>(c)) < samples[c].size()) return false;
    }
  }
  return true;
}

// Ends the logger once every sample has been served and the last frame is
// due, or when the user presses Ctrl-C.
void stop_when_replayed(const sim::RecordedRun& recorded,
                        const std::vector<std::unique_ptr<sim::ModbusSimServer>>& servers, double speed,
                        std::atomic<bool>& stop) {
  const auto frames_done = std::chrono::steady_clock::now() +
                           std::chrono::nanoseconds(static_cast<std::int64_t>(recorded.last_offset_ns / speed)) + 1s;
  const auto& interrupted = stop_requested_by_signal();
  while (!stop && !interrupted) {
    if (every_sample_served(recorded, servers) && std::chrono::steady_clock::now() > frames_done) break;
    std::this_thread::sleep_for(20ms);
  }
  stop = true;
}

// The recorded run's markers (its declared origin among them) at the same
// place in the replay: the replay starts where the recording did.
void copy_markers(const sim::RecordedRun& recorded, double speed, std::int64_t started_ns, storage::RunStore& store) {
  std::vector<storage::Event> markers;
  for (const auto& e : storage::RunStore::open(recorded.dir).events()) {
    if (e.kind != "marker") continue;
    const auto offset_ns = static_cast<double>(e.t_ns - recorded.run.started_ns) / speed;
    markers.push_back({0, std::nullopt, started_ns + static_cast<std::int64_t>(offset_ns), "marker", e.message});
  }
  store.write_events(markers);
}

// The polls and frames stamped with the recording's times (sim/replay.h),
// so the devices keep their timing between them; what could not be matched
// keeps its wall-clock time and is named.
void stamp_recorded_times(const sim::RecordedRun& recorded, const std::filesystem::path& dir, std::int64_t started_ns,
                          double speed) {
  const sim::RecordingTimes times = sim::stamp_from_recording(recorded, dir, started_ns, speed);
  for (const std::string& problem : times.problems) spdlog::warn("{}: {}", dir.string(), problem);
  spdlog::info(
      "{} samples and {} frames stamped with the recording's times, scaled by the speed-up (the largest moved "
      "{:.1f} ms from its poll or arrival)",
      times.samples, times.frames, times.largest_move_s * 1e3);
}

void replay(const ReplayArgs& args) {
  refuse_standard_output(args.out, "--out", "a run is a folder (run.sqlite, frames/)");
  check_new_run_output(args.out, "--out");  // not the recorded run itself, nor inside its own folders
  const sim::RecordedRun recorded = sim::inspect_recorded_run(args.run);
  for (const std::string& problem : recorded.problems) spdlog::warn("{}: {}", args.run, problem);
  if (recorded.devices.empty() && recorded.cameras.empty()) throw std::runtime_error(args.run + ": nothing to replay");

  std::vector<std::unique_ptr<sim::ModbusSimServer>> servers;
  std::vector<int> ports;
  for (const sim::ReplayDevice& device : recorded.devices) {
    servers.push_back(std::make_unique<sim::ModbusSimServer>(sim::replay_module_options(device, 0)));
    servers.back()->start();
    ports.push_back(servers.back()->port());
  }
  const std::string toml = sim::replay_experiment_toml(recorded, ports, args.speed);
  const auto config = acquisition::parse_experiment(toml, "replay.toml");
  const std::int64_t started_ns = acquisition::utc_now_ns();
  auto store = storage::RunStore::create(args.out, acquisition::run_info(config, started_ns),
                                         storage::RunStore::CreateMode::kNew);
  copy_markers(recorded, args.speed, started_ns, store);
  if (pipeline::inherit_settings(args.run, args.out)) {
    spdlog::info("the recorded run's processing settings are the replay's: `bosfuse process {}` repeats them",
                 args.out);
  }
  acquisition::Logger::Options options;
  options.on_progress = [](const std::string& line) { spdlog::info("{}", line); };
  acquisition::Logger logger(store, options);
  logger.add_devices(config);
  spdlog::info("replaying {} at {}x into {}", args.run, args.speed, args.out);

  std::atomic<bool> stop{false};
  std::thread watcher([&] { stop_when_replayed(recorded, servers, args.speed, stop); });
  acquisition::Logger::Summary summary;
  try {
    summary = logger.run(stop);
  } catch (...) {
    stop = true;
    watcher.join();
    throw;
  }
  watcher.join();
  stamp_recorded_times(recorded, store.dir(), started_ns, args.speed);
  std::cout << summary.BriefReport() << "\nreplayed run: " << store.dir().string() << "\n";
}

void add_replay(CLI::App& root) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = root.add_subcommand(
      "replay", "Record a recorded run again through simulated devices (Modbus on loopback, a replayed camera)");
  cmd->add_option("run", args->run, "Recorded run folder")->required()->transform(run_folder_argument());
  cmd->add_option("--out,-o", args->out, "New run folder to create")->required();
  cmd->add_option("--speed", args->speed, "Replay N times faster than recorded (the new run's time scale is the "
                                          "recorded run's times N)")
      ->check(CLI::Range(0.01, 10000.0))
      ->capture_default_str();
  cmd->callback([args] { replay(*args); });
}

BOSFUSE_COMMAND(add_replay);

}  // namespace
}  // namespace bosfuse::app
