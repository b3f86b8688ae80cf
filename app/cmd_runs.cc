// bosfuse runs: what a run folder holds.

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>

#include "acquisition/clock.h"
#include "app/command.h"
#include "app/run_argument.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"
#include "storage/value_digits.h"

namespace bosfuse::app {
namespace {

std::string time_or_dash(const std::optional<std::int64_t>& t_ns) {
  return t_ns ? acquisition::format_iso8601_utc(*t_ns, 3) : "-";
}

// At the channel's digits (storage/value_digits.h).
std::string value_or_dash(const std::optional<double>& v, std::optional<double> resolution) {
  return v ? storage::format_channel_value(*v, resolution) : "-";
}

std::string resolution_or_dash(std::optional<double> resolution) {
  return resolution ? fmt::format("{:g}", *resolution) : "-";
}

void print_run(const storage::RunStore& store) {
  const storage::RunInfo run = store.run();
  const std::string status = run.status == storage::RunStatus::kRunning ? "running (a logger is recording it now)"
                                                                        : std::string(storage::to_string(run.status));
  std::cout << fmt::format("run       {}\nfolder    {}\nstatus    {}\nstarted   {}\nended     {}\n", run.name,
                           store.dir().string(), status, acquisition::format_iso8601_utc(run.started_ns, 3),
                           time_or_dash(run.ended_ns));
  if (run.ended_ns) {
    std::cout << fmt::format("duration  {:.1f} s recorded\n",
                             static_cast<double>(*run.ended_ns - run.started_ns) * 1e-9);
  }
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  std::cout << "time      " << clock.basis() << "\n";
  if (!clock.note.empty()) std::cout << "          " << clock.note << "\n";
}

void print_channels(const storage::RunStore& store) {
  std::cout << fmt::format("\n{:<12} {:<16} {:<13} {:<5} {:>10} {:>9} {:>9} {:>9} {:>9}  {:<24} {}\n", "device",
                           "channel", "kind", "unit", "resolution", "samples", "ok", "min", "max", "first", "last");
  for (const auto& s : store.channel_summaries()) {
    const auto resolution = s.channel.resolution;
    std::cout << fmt::format("{:<12} {:<16} {:<13} {:<5} {:>10} {:>9} {:>9} {:>9} {:>9}  {:<24} {}\n", s.device_name,
                             s.channel.name, s.channel.kind, s.channel.unit, resolution_or_dash(resolution),
                             s.sample_count, s.ok_count, value_or_dash(s.min_value, resolution),
                             value_or_dash(s.max_value, resolution), time_or_dash(s.first_ns), time_or_dash(s.last_ns));
  }
}

// A marker's experiment time, and whether it is the run's t = 0.
std::string marker_time(const storage::ExperimentClock& clock, const storage::Event& e) {
  if (e.kind != "marker") return "";
  if (e.t_ns == clock.origin_ns && clock.origin_name == e.message) return "  (t = 0, the run's origin)";
  return fmt::format("  (t = {:.3f} s)", clock.seconds(e.t_ns));
}

void print_events(const storage::RunStore& store) {
  const auto events = store.events();
  std::map<std::string, int> counts;
  for (const auto& e : events) ++counts[e.kind];
  std::cout << "\nevents   ";
  for (const auto& [kind, n] : counts) std::cout << " " << kind << " " << n;
  std::cout << "\n";
  std::map<std::int64_t, std::string> device_names;
  for (const auto& d : store.devices()) device_names[d.id] = d.name;
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  for (const auto& e : events) {
    if (e.kind == "started" || e.kind == "stopped" || e.kind == "connect") continue;
    std::cout << fmt::format("  {}  {:<10} {:<12} {}{}\n", acquisition::format_iso8601_utc(e.t_ns, 3), e.kind,
                             e.device_id ? device_names[*e.device_id] : "", e.message, marker_time(clock, e));
  }
  std::cout << fmt::format("frames    {}\n", store.frames().size());
}

// The run folders under `dir`, in name order; a run's own folder is not
// searched further (its frames/ and fields/ hold no runs).
std::vector<std::filesystem::path> runs_under(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::vector<fs::path> runs;
  for (auto it = fs::recursive_directory_iterator(dir, fs::directory_options::skip_permission_denied);
       it != fs::recursive_directory_iterator(); ++it) {
    if (!it->is_directory()) continue;
    if (storage::RunStore::holds_run(it->path())) {
      runs.push_back(it->path());
      it.disable_recursion_pending();
    }
  }
  std::sort(runs.begin(), runs.end());
  return runs;
}

void print_run_list(const std::filesystem::path& dir) {
  const auto runs = runs_under(dir);
  if (runs.empty()) throw std::runtime_error("'" + dir.string() + "' holds no bosfuse run, nor any folder below it");
  std::cout << fmt::format("{:<40} {:<16} {:<12} {:<24} {:>10} {:>9} {:>7}\n", "folder", "name", "status", "started",
                           "duration", "samples", "frames");
  // A run this bosfuse may not read (a newer schema, a damaged file) is
  // said on stderr; the others are still listed, and the exit says so.
  std::vector<std::string> refused;
  for (const auto& run_dir : runs) {
    std::optional<storage::RunStore> opened;
    try {
      opened.emplace(storage::RunStore::open(run_dir));
    } catch (const storage::StorageError& e) {
      std::cerr << e.what() << "\n";
      refused.push_back(std::filesystem::relative(run_dir, dir).string());
      continue;
    }
    const storage::RunStore& store = *opened;
    const storage::RunInfo run = store.run();
    std::int64_t samples = 0;
    for (const auto& channel : store.channel_summaries()) samples += channel.sample_count;
    const std::string duration =
        run.ended_ns ? fmt::format("{:.1f} s", static_cast<double>(*run.ended_ns - run.started_ns) * 1e-9) : "-";
    std::cout << fmt::format("{:<40} {:<16} {:<12} {:<24} {:>10} {:>9} {:>7}\n",
                             std::filesystem::relative(run_dir, dir).string(), run.name, storage::to_string(run.status),
                             acquisition::format_iso8601_utc(run.started_ns, 0), duration, samples,
                             store.frames().size());
  }
  if (!refused.empty()) {
    std::string names;
    for (const auto& name : refused) names += (names.empty() ? "" : ", ") + name;
    throw std::runtime_error(fmt::format("{} of {} runs could not be read: {}", refused.size(), runs.size(), names));
  }
}

void add_runs(CLI::App& root) {
  auto dir = std::make_shared<std::string>();
  CLI::App* cmd = root.add_subcommand(
      "runs", "Summarise a run (channels, sample counts, time span, events), or list the runs under a folder");
  cmd->add_option("run", *dir, "Run folder, or a folder holding runs")->required()->transform(run_folder_argument());
  cmd->callback([dir] {
    if (!storage::RunStore::holds_run(*dir) && std::filesystem::is_directory(*dir)) {
      print_run_list(*dir);
      return;
    }
    const auto store = storage::RunStore::open(*dir);
    print_run(store);
    print_channels(store);
    print_events(store);
  });
}

BOSFUSE_COMMAND(add_runs);

}  // namespace
}  // namespace bosfuse::app
