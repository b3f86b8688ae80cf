#include "sim/replay_session.h"

#include <spdlog/spdlog.h>

#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::sim {
namespace {

using namespace std::chrono_literals;
using Servers = std::vector<std::unique_ptr<ModbusSimServer>>;

// The recorded run, its problems said; refused when nothing of it can be replayed.
RecordedRun replayable_run(const std::filesystem::path& dir) {
  RecordedRun recorded = inspect_recorded_run(dir);
  for (const std::string& problem : recorded.problems) spdlog::warn("{}: {}", dir.string(), problem);
  if (recorded.devices.empty() && recorded.cameras.empty())
    throw std::runtime_error(dir.string() + ": nothing to replay");
  return recorded;
}

Servers start_servers(const RecordedRun& recorded) {
  Servers servers;
  for (const ReplayDevice& device : recorded.devices) {
    servers.push_back(std::make_unique<ModbusSimServer>(replay_module_options(device, 0)));
    servers.back()->start();
  }
  return servers;
}

acquisition::ExperimentConfig replay_experiment(const RecordedRun& recorded, const Servers& servers, double speed) {
  std::vector<int> ports;
  for (const auto& server : servers) ports.push_back(server->port());
  return acquisition::parse_experiment(replay_experiment_toml(recorded, ports, speed), "replay.toml");
}

bool every_sample_served(const RecordedRun& recorded, const Servers& servers) {
  for (std::size_t d = 0; d < servers.size(); ++d) {
    const auto& samples = recorded.devices[d].samples;
    for (std::size_t c = 0; c < samples.size(); ++c) {
      if (servers[d]->draws(static_cast<int>(c)) < samples[c].size()) return false;
    }
  }
  return true;
}

// Ends the logger once every sample has been served and the last frame is
// due, or when the caller interrupts.
void stop_when_replayed(const RecordedRun& recorded, const Servers& servers, double speed,
                        const std::atomic<bool>& interrupted, std::atomic<bool>& stop) {
  const auto frames_done = std::chrono::steady_clock::now() +
                           std::chrono::nanoseconds(static_cast<std::int64_t>(recorded.last_offset_ns / speed)) + 1s;
  while (!stop && !interrupted) {
    if (every_sample_served(recorded, servers) && std::chrono::steady_clock::now() > frames_done) break;
    std::this_thread::sleep_for(20ms);
  }
  stop = true;
}

// The recorded run's markers (its declared origin among them) at the same
// place in the replay: the replay starts where the recording did.
void copy_markers(const RecordedRun& recorded, double speed, std::int64_t started_ns, storage::RunStore& store) {
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
void stamp_recorded_times(const RecordedRun& recorded, const std::filesystem::path& dir, std::int64_t started_ns,
                          double speed) {
  const RecordingTimes times = stamp_from_recording(recorded, dir, started_ns, speed);
  for (const std::string& problem : times.problems) spdlog::warn("{}: {}", dir.string(), problem);
  spdlog::info(
      "{} samples and {} frames stamped with the recording's times, scaled by the speed-up (the largest moved "
      "{:.1f} ms from its poll or arrival)",
      times.samples, times.frames, times.largest_move_s * 1e3);
}

}  // namespace

ReplaySession::ReplaySession(const std::filesystem::path& recorded_run, const std::filesystem::path& out, double speed)
    : recorded_run_(recorded_run),
      out_(out),
      speed_(speed),
      recorded_(replayable_run(recorded_run)),
      servers_(start_servers(recorded_)),
      config_(replay_experiment(recorded_, servers_, speed)),
      started_ns_(acquisition::utc_now_ns()),
      store_(storage::RunStore::create(out, acquisition::run_info(config_, started_ns_),
                                       storage::RunStore::CreateMode::kNew)) {
  copy_markers(recorded_, speed_, started_ns_, store_);
}

ReplaySession::~ReplaySession() {
  stop_ = true;
  if (watcher_.joinable()) watcher_.join();
}

acquisition::Logger::Summary ReplaySession::run(const std::atomic<bool>& interrupted) {
  if (ran_) throw std::logic_error("a replay session runs once");
  ran_ = true;
  acquisition::LoggerOptions options;
  options.on_progress = [](const std::string& line) { spdlog::info("{}", line); };
  acquisition::Logger logger(store_, options);
  logger.add_devices(config_);
  spdlog::info("replaying {} at {}x into {}", recorded_run_.string(), speed_, out_.string());
  watcher_ = std::thread([this, &interrupted] { stop_when_replayed(recorded_, servers_, speed_, interrupted, stop_); });
  const acquisition::Logger::Summary summary = logger.run(stop_);
  watcher_.join();  // the watcher ends by itself once all is replayed
  stamp_recorded_times(recorded_, store_.dir(), started_ns_, speed_);
  return summary;
}

}  // namespace bosfuse::sim
