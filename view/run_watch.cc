#include "view/run_watch.h"

#include <nlohmann/json.hpp>

#include "acquisition/config/experiment_config.h"
#include "storage/value_digits.h"
#include "view/thread_priority.h"

namespace bosfuse::view {
namespace {

// The clock's origin is the run's first sample (a scan of every sample) or
// a marker; a marker arrives with an event, the first sample can move only
// while the first batches commit. Rechecking it on every new event, and at
// most this often otherwise, keeps a long run's poll cheap.
constexpr auto kClockRecheckPeriod = std::chrono::seconds(1);

// The alarm limits of the run's experiment file by (device, channel) name,
// as the page shows them; none when the stored file is not one this build
// reads (an old or hand-made run).
std::map<std::pair<std::string, std::string>, nlohmann::json> alarm_limits_json(const std::string& config_toml) {
  std::map<std::pair<std::string, std::string>, nlohmann::json> out;
  try {
    for (const auto& c : acquisition::alarm_limits(acquisition::parse_experiment(config_toml, "the run's experiment file"))) {
      nlohmann::json j = nlohmann::json::object();
      if (c.limits.low) j["low"] = *c.limits.low;
      if (c.limits.high) j["high"] = *c.limits.high;
      if (c.limits.rate_per_min) j["rate_per_min"] = *c.limits.rate_per_min;
      if (c.limits.stale_s) j["stale_s"] = *c.limits.stale_s;
      out[{c.device, c.channel}] = j;
    }
  } catch (const std::exception&) {
    // Limits are shown when the file reads; the run itself is served either way.
  }
  return out;
}

bool same_clock(const storage::ExperimentClock& a, const storage::ExperimentClock& b) {
  return a.origin_ns == b.origin_ns && a.time_scale == b.time_scale && a.origin_name == b.origin_name &&
         a.note == b.note;
}

}  // namespace

RunWatch::RunWatch(const std::filesystem::path& run_dir, std::chrono::milliseconds poll_period)
    : run_dir_(run_dir),
      poll_period_(poll_period),
      store_(storage::RunStore::open(run_dir)),
      alarm_limits_(alarm_limits_json(store_.run().config_toml)),
      tail_(run_dir) {
  snapshot_.head = tail_.head();
  snapshot_.status = tail_.run_status();
  refresh_description();
  snapshot_.clock = storage::experiment_clock(store_);
  clock_checked_ = std::chrono::steady_clock::now();
  snapshot_.generation = 1;
  poller_ = std::thread([this] {
    yield_to_the_logger();
    poll_until_stopped();
  });
}

RunWatch::~RunWatch() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (poller_.joinable()) poller_.join();
}

RunSnapshot RunWatch::snapshot() const {
  std::lock_guard lock(mutex_);
  return snapshot_;
}

RunSnapshot RunWatch::wait_for_change(std::uint64_t seen, std::chrono::milliseconds limit) const {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, limit, [&] { return stopping_ || snapshot_.generation != seen; });
  return snapshot_;
}

void RunWatch::notify() {
  {
    std::lock_guard lock(mutex_);
    ++snapshot_.generation;
  }
  changed_.notify_all();
}

void RunWatch::poll_until_stopped() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    changed_.wait_for(lock, poll_period_, [&] { return stopping_; });
    if (stopping_) break;
    lock.unlock();
    try {
      poll_once();
    } catch (const std::exception&) {
      // A busy or briefly unreadable store is read again at the next poll.
    }
    lock.lock();
  }
}

void RunWatch::poll_once() {
  const TailCursor head = tail_.head();
  const std::string status = tail_.run_status();
  std::lock_guard lock(mutex_);
  const bool rows_changed = !(head == snapshot_.head);
  const bool events_changed = head.event_id != snapshot_.head.event_id;
  const auto now = std::chrono::steady_clock::now();
  bool changed = rows_changed || status != snapshot_.status;
  if (events_changed || (rows_changed && now - clock_checked_ >= kClockRecheckPeriod)) {
    const storage::ExperimentClock clock = storage::experiment_clock(store_);
    clock_checked_ = now;
    if (!same_clock(clock, snapshot_.clock)) {
      snapshot_.clock = clock;
      changed = true;
    }
  }
  if (events_changed) refresh_description();  // a device joins a run with an event
  if (!changed) return;
  snapshot_.head = head;
  snapshot_.status = status;
  ++snapshot_.generation;
  changed_.notify_all();
}

void RunWatch::refresh_description() {
  snapshot_.device_names.clear();
  for (const auto& device : store_.devices()) snapshot_.device_names[device.id] = device.name;
}

std::string RunWatch::describe_json() const {
  std::lock_guard lock(mutex_);
  const storage::RunInfo run = store_.run();
  nlohmann::json devices = nlohmann::json::array();
  std::map<std::int64_t, std::string> names;
  for (const auto& device : store_.devices()) {
    names[device.id] = device.name;
    devices.push_back({{"id", device.id},
                       {"name", device.name},
                       {"kind", device.kind},
                       {"profile", device.profile},
                       {"address", device.address}});
  }
  nlohmann::json channels = nlohmann::json::array();
  for (const auto& channel : store_.channels()) {
    const auto alarms = alarm_limits_.find({names[channel.device_id], channel.name});
    const std::optional<int> decimals = storage::resolution_decimals(channel.resolution);
    channels.push_back({{"id", channel.id},
                        {"name", channel.name},
                        {"kind", channel.kind},
                        {"unit", channel.unit},
                        {"tc_type", channel.tc_type ? nlohmann::json(*channel.tc_type) : nlohmann::json()},
                        {"resolution", channel.resolution ? nlohmann::json(*channel.resolution) : nlohmann::json()},
                        // The page prints values at these (null: 6 significant digits).
                        {"decimals", decimals ? nlohmann::json(*decimals) : nlohmann::json()},
                        {"device_id", channel.device_id},
                        {"device", names[channel.device_id]},
                        {"alarms", alarms == alarm_limits_.end() ? nlohmann::json::object() : alarms->second}});
  }
  const storage::ExperimentClock& clock = snapshot_.clock;
  return nlohmann::json{{"name", run.name},
                        {"status", snapshot_.status},
                        {"time_basis", clock.basis()},
                        {"origin", clock.origin_name},
                        {"time_scale", clock.time_scale},
                        {"clock_note", clock.note},
                        {"devices", devices},
                        {"channels", channels}}
      .dump();
}

}  // namespace bosfuse::view
