#include "sim/replay.h"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "acquisition/config/experiment_config.h"
#include "storage/database.h"
#include "storage/record_rows.h"
#include "storage/run_paths.h"
#include "storage/run_store.h"
#include "storage/transaction.h"

namespace bosfuse::sim {
namespace fs = std::filesystem;
namespace {

using storage::SampleStatus;

constexpr double kOpenCircuitCode = -9999;
constexpr double kOutOfRangeCode = -8888;

double served_value(const storage::Sample& sample) {
  switch (sample.status) {
    case SampleStatus::kOk:
      return sample.value.value_or(std::nan(""));
    case SampleStatus::kOpenCircuit:
      return kOpenCircuitCode;
    case SampleStatus::kOutOfRange:
      return kOutOfRangeCode;
    default:
      return std::nan("");
  }
}

// later − earlier for two times of one run. A damaged store (times centuries
// apart, which no run spans) is refused instead of overflowing.
std::int64_t span_ns(std::int64_t later, std::int64_t earlier) {
  static constexpr std::int64_t kLongestRunNs = 100LL * 366 * 86400 * 1'000'000'000;
  std::int64_t span = 0;
  if (__builtin_sub_overflow(later, earlier, &span) || span > kLongestRunNs || span < -kLongestRunNs) {
    throw std::runtime_error("the run's times are damaged: " + std::to_string(later) + " ns and " +
                             std::to_string(earlier) + " ns lie more than a century apart");
  }
  return span;
}

// The poll period a replay uses: the mean interval between recorded
// samples, leaving out gaps of more than three median intervals (an outage,
// which a replay does not reproduce). Polls a loaded logger skipped are in
// the mean, so the replay spreads the samples over the time they took: with
// the median alone a record with skipped polls replays compressed, and its
// cooling rate comes out too high.
std::chrono::nanoseconds typical_interval(const std::vector<storage::Sample>& samples) {
  std::vector<std::int64_t> gaps;
  for (std::size_t i = 1; i < samples.size(); ++i) gaps.push_back(span_ns(samples[i].t_ns, samples[i - 1].t_ns));
  if (gaps.empty()) return std::chrono::seconds(1);
  std::vector<std::int64_t> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const std::int64_t median = sorted[sorted.size() / 2];
  // In double: three times a gap of a century overflows 64-bit nanoseconds.
  const double outage_ns = 3.0 * static_cast<double>(median);
  double sum = 0;
  std::size_t count = 0;
  for (const std::int64_t gap : gaps) {
    if (static_cast<double>(gap) > outage_ns) continue;
    sum += static_cast<double>(gap);
    ++count;
  }
  // A damaged file read out of time order can leave no gap below the bound.
  const double mean_ns = count > 0 ? sum / static_cast<double>(count) : static_cast<double>(median);
  return std::chrono::nanoseconds(std::max<std::int64_t>(static_cast<std::int64_t>(mean_ns), 1'000'000));
}

std::string number(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

// `time_constants`: the recorded file's time_constant_s by channel_name_key
// (processing de-lags a thermocouple by it, so a replay must keep it).
toml::table channel_table(const storage::ChannelInfo& channel, std::size_t index,
                          const std::map<std::string, double>& time_constants) {
  toml::table t{{"name", channel.name},
                {"kind", channel.kind},
                {"unit", channel.unit},
                {"register", "holding"},
                {"address", static_cast<std::int64_t>(2 * index)},
                {"type", "float32"},
                {"open_circuit_codes", toml::array{kOpenCircuitCode}},
                {"out_of_range_codes", toml::array{kOutOfRangeCode}}};
  if (channel.tc_type) t.insert("tc_type", *channel.tc_type);
  if (channel.image_x_px && channel.image_y_px) {
    t.insert("position_px", toml::array{*channel.image_x_px, *channel.image_y_px});
  }
  if (const auto tau = time_constants.find(acquisition::channel_name_key(channel.name)); tau != time_constants.end())
    t.insert("time_constant_s", tau->second);
  // The replay serves floats, which have no step of their own: the recorded
  // channel's resolution is kept by stating it.
  if (channel.resolution) t.insert("resolution", *channel.resolution);
  return t;
}

toml::table device_table(const ReplayDevice& device, int port, double speed,
                         const std::map<std::string, double>& time_constants) {
  // Within the periods the logger accepts: a replay serves sample k at poll
  // k whatever the period, and a record whose samples lie years apart (a
  // damaged clock) still replays, at a poll a year.
  const double period_s = std::clamp(std::chrono::duration<double>(device.period).count() / speed,
                                     acquisition::kShortestPollPeriodS, acquisition::TomlReader::kLongestSeconds);
  toml::array channels;
  for (std::size_t c = 0; c < device.channels.size(); ++c) channels.push_back(channel_table(device.channels[c], c, time_constants));
  return toml::table{{"name", device.name},
                     {"profile", "generic"},
                     {"transport", "tcp"},
                     {"host", "127.0.0.1"},
                     {"port", port},
                     {"poll_period_s", period_s},
                     {"timeout_s", 1.0},
                     {"poll_count", static_cast<std::int64_t>(device.samples.front().size())},
                     {"channels", std::move(channels)}};
}

// A frame whose stored path leads outside the run is refused by name and
// skipped like a missing one: nothing outside the run is copied into the new one.
void inspect_frames(const storage::RunStore& store, RecordedRun& recorded) {
  for (const auto& device : store.devices()) {
    if (device.kind != "camera") continue;
    std::size_t present = 0, missing = 0;
    for (const auto& frame : store.frames()) {
      if (frame.device_id != device.id) continue;
      try {
        (fs::exists(storage::resolve_in_run(recorded.dir, frame.path)) ? present : missing) += 1;
      } catch (const storage::StorageError& e) {
        recorded.problems.push_back("camera " + device.name + ": frame " + std::to_string(frame.id) + ": " + e.what() +
                                    "; it is skipped");
        missing += 1;
      }
      recorded.last_offset_ns = std::max(recorded.last_offset_ns, span_ns(frame.t_ns, recorded.run.started_ns));
    }
    if (missing > 0) {
      recorded.problems.push_back("camera " + device.name + ": " + std::to_string(missing) + " of " +
                                  std::to_string(missing + present) + " frame files are missing; they are skipped");
    }
    if (present > 0) recorded.cameras.push_back(device.name);
  }
}

}  // namespace

RecordedRun inspect_recorded_run(const fs::path& dir) {
  const storage::RunStore store = storage::RunStore::open(dir);
  RecordedRun recorded{dir, store.run(), {}, {}, {}, 0};
  if (recorded.run.status == storage::RunStatus::kRunning) {
    recorded.problems.push_back("the run is still being recorded; replaying what it has committed so far");
  } else if (recorded.run.status == storage::RunStatus::kInterrupted) {
    recorded.problems.push_back("the run was interrupted (see its events); replaying what it committed");
  }
  const auto channels = store.channels();
  for (const auto& device : store.devices()) {
    if (device.kind == "camera") continue;
    ReplayDevice replay{device.name, {}, {}, {}};
    for (const auto& channel : channels) {
      if (channel.device_id != device.id) continue;
      replay.channels.push_back(channel);
      replay.samples.push_back(store.read_samples(channel.id));
      if (!replay.samples.back().empty()) {
        recorded.last_offset_ns =
            std::max(recorded.last_offset_ns, span_ns(replay.samples.back().back().t_ns, recorded.run.started_ns));
      }
    }
    if (replay.channels.empty() || replay.samples.front().empty()) {
      recorded.problems.push_back("device " + device.name + " has no samples; not replayed");
      continue;
    }
    replay.period = typical_interval(replay.samples.front());
    recorded.devices.push_back(std::move(replay));
  }
  inspect_frames(store, recorded);
  return recorded;
}

ModbusSimServerOptions replay_module_options(const ReplayDevice& device, int port) {
  ModbusSimServerOptions options;
  options.endpoint.host = "127.0.0.1";
  options.endpoint.port = port;
  for (std::size_t i = 0; i < device.channels.size(); ++i) {
    acquisition::ModbusChannel map;
    map.name = device.channels[i].name;
    map.function = acquisition::RegisterKind::kHolding;
    map.address = static_cast<int>(2 * i);
    map.type = acquisition::DataType::kFloat32;
    map.open_circuit_codes = {kOpenCircuitCode};
    map.out_of_range_codes = {kOutOfRangeCode};
    options.channels.push_back(map);
  }
  // Served by draw, not by time: poll k of the new run gets sample k.
  options.temperature_c = [samples = device.samples](int channel, double, std::uint64_t draw) {
    const auto& series = samples[static_cast<std::size_t>(channel)];
    return draw < series.size() ? served_value(series[draw]) : std::nan("");
  };
  return options;
}

namespace {

// The recorded experiment file's tables that processing reads — the optical
// set-up, the clock alignment and the agreement's margins — so the replayed
// run processes like the recorded one. A file that does not parse (a
// damaged run) gives nothing to copy; the replay still runs.
void copy_processing_tables(const std::string& recorded_toml, toml::table& document) {
  toml::table recorded;
  try {
    recorded = toml::parse(recorded_toml);
  } catch (const toml::parse_error&) {
    return;
  }
  for (const char* name : {"geometry", "alignment", "agreement"}) {
    if (const toml::table* table = recorded[name].as_table()) document.insert(name, *table);
  }
}

// Each recorded channel's time_constant_s (channel_time_constants); none
// from a file that does not parse.
std::map<std::string, double> recorded_time_constants(const std::string& recorded_toml) {
  try {
    return acquisition::channel_time_constants(acquisition::parse_experiment(recorded_toml, "recorded experiment"));
  } catch (const acquisition::ConfigError&) {
    return {};
  }
}

}  // namespace

std::string replay_experiment_toml(const RecordedRun& run, const std::vector<int>& ports, double speed) {
  // Built as a toml++ table, not by hand: names come from a recorded run and
  // may hold any character (control characters, quotes, non-ASCII), which
  // toml++ escapes so the logger reads back exactly the same string.
  const std::map<std::string, double> time_constants = recorded_time_constants(run.run.config_toml);
  toml::array devices;
  for (std::size_t d = 0; d < run.devices.size(); ++d)
    devices.push_back(device_table(run.devices[d], ports.at(d), speed, time_constants));
  toml::array cameras;
  for (const std::string& camera : run.cameras) {
    cameras.push_back(toml::table{{"name", camera},
                                  {"source", "replay"},
                                  {"run", run.dir.string()},
                                  {"camera", camera},
                                  {"speed", speed},
                                  {"reference_frames", 0}});
  }
  toml::table run_table{{"name", "replay of " + run.run.name}, {"time_scale", run.run.time_scale * speed}};
  if (run.run.origin_event) run_table.insert("origin", *run.run.origin_event);
  toml::table document{{"run", std::move(run_table)}};
  copy_processing_tables(run.run.config_toml, document);
  if (!devices.empty()) document.insert("devices", std::move(devices));
  if (!cameras.empty()) document.insert("cameras", std::move(cameras));
  std::ostringstream toml;
  toml << "# Replay of a recorded run at " << number(speed) << "x, written by bosfuse replay.\n" << document << "\n";
  return toml.str();
}

namespace {

// A recorded time on the replay's clock.
std::int64_t replay_time_ns(std::int64_t recorded_ns, const RecordedRun& recorded, std::int64_t started_ns,
                            double speed) {
  return started_ns + std::llround(static_cast<double>(span_ns(recorded_ns, recorded.run.started_ns)) / speed);
}

// A poll that failed reached no module's sample: it drew nothing.
bool failed_poll(int status) {
  return status == static_cast<int>(SampleStatus::kTimeout) || status == static_cast<int>(SampleStatus::kBadReply);
}

std::string fmt_count(const std::string& label, std::size_t served, std::size_t recorded) {
  return "channel " + label + ": " + std::to_string(served) + " samples replayed for " + std::to_string(recorded) +
         " recorded; its times are those of the polls";
}

// One replayed channel's samples onto its recorded ones, in order.
void stamp_channel(storage::Database& db, std::int64_t channel_id, const std::string& label,
                   const std::vector<storage::Sample>& recorded_samples, const RecordedRun& recorded,
                   std::int64_t started_ns, double speed, RecordingTimes& out) {
  std::vector<std::pair<std::int64_t, std::int64_t>> served;  // rowid, poll time
  auto rows = db.prepare("SELECT rowid, t_ns, status FROM samples WHERE channel_id = ? ORDER BY t_ns");
  rows.bind(1, channel_id);
  while (rows.step()) {
    if (!failed_poll(static_cast<int>(rows.column_int64(2)))) served.emplace_back(rows.column_int64(0), rows.column_int64(1));
  }
  if (served.size() > recorded_samples.size()) {
    out.problems.push_back(fmt_count(label, served.size(), recorded_samples.size()));
    return;
  }
  auto update = db.prepare("UPDATE samples SET t_ns = ? WHERE rowid = ?");
  for (std::size_t k = 0; k < served.size(); ++k) {
    const std::int64_t t_ns = replay_time_ns(recorded_samples[k].t_ns, recorded, started_ns, speed);
    out.largest_move_s = std::max(out.largest_move_s, std::abs(static_cast<double>(served[k].second - t_ns)) * 1e-9);
    update.bind_all(t_ns, served[k].first).run();
    ++out.samples;
  }
}

}  // namespace

RecordingTimes stamp_from_recording(const RecordedRun& recorded, const fs::path& replayed_dir, std::int64_t started_ns,
                                    double speed) {
  RecordingTimes out;
  const storage::RunStore replayed = storage::RunStore::open(replayed_dir);
  std::map<std::int64_t, std::string> device_names;
  for (const auto& d : replayed.devices()) device_names[d.id] = d.name;
  storage::Database db(storage::database_path(replayed_dir), storage::Database::Mode::kReadWrite);
  storage::Transaction transaction(db);
  for (const ReplayDevice& device : recorded.devices) {
    for (const auto& channel : replayed.channels()) {
      if (device_names[channel.device_id] != device.name) continue;
      for (std::size_t c = 0; c < device.channels.size(); ++c) {
        if (device.channels[c].name != channel.name) continue;
        stamp_channel(db, channel.id, device.name + "/" + channel.name, device.samples[c], recorded, started_ns,
                      speed, out);
      }
    }
  }
  auto update = db.prepare("UPDATE frames SET t_ns = ? WHERE id = ?");
  for (const auto& frame : replayed.frames()) {
    if (!frame.device_t_ns) continue;  // not served by a replayed camera
    const std::int64_t t_ns = replay_time_ns(*frame.device_t_ns, recorded, started_ns, speed);
    out.largest_move_s = std::max(out.largest_move_s, std::abs(static_cast<double>(frame.t_ns - t_ns)) * 1e-9);
    update.bind_all(t_ns, frame.id).run();
    ++out.frames;
  }
  transaction.commit();
  return out;
}

}  // namespace bosfuse::sim
