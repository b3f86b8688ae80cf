#include "acquisition/device_poller.h"

#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::acquisition {
namespace {

// How long a wait for the next poll goes without checking for stale channels.
constexpr std::chrono::seconds kStaleCheckInterval{1};

AlarmMonitor watch_alarms(const std::string& device, const std::vector<storage::ChannelInfo>& channels,
                          const std::vector<std::int64_t>& channel_ids, const std::vector<AlarmLimits>& limits) {
  if (limits.empty()) return AlarmMonitor({}, utc_now_ns());
  if (limits.size() != channels.size() || channel_ids.size() != channels.size()) {
    throw std::invalid_argument("device " + device + ": alarm limits do not match its channels");
  }
  std::vector<AlarmMonitor::Channel> watched;
  for (std::size_t i = 0; i < channels.size(); ++i) {
    watched.push_back({channel_ids[i], channels[i].name, channels[i].unit, limits[i], channels[i].resolution});
  }
  try {
    return AlarmMonitor(watched, utc_now_ns());
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("device " + device + ": " + e.what());
  }
}

}  // namespace

std::string DevicePollerOptions::Validate() const {
  if (period <= std::chrono::nanoseconds::zero()) return "poll period must be positive";
  if (poll_count && *poll_count < 1) return "poll count must be at least 1";
  if (skipped_event_interval <= std::chrono::nanoseconds::zero()) return "skipped-poll event interval must be positive";
  if (recovery_polls < 1) return "recovery polls must be at least 1";
  return ConnectionKeeper::Backoff{backoff_initial, backoff_max}.Validate();
}

DevicePoller::DevicePoller(std::unique_ptr<ThermocoupleSource> source, std::int64_t device_id,
                           std::vector<std::int64_t> channel_ids, storage::RunWriter& writer, DevicePollerOptions options)
    : DeviceWorker(source->device_info().name, device_id, writer),
      source_(std::move(source)),
      channel_ids_(std::move(channel_ids)),
      channels_(source_->channel_infos()),
      options_(options),
      schedule_origin_(std::chrono::steady_clock::now()),
      connection_(
          {options.backoff_initial, options.backoff_max},
          [this](const std::string& kind, const std::string& message) { record_event(kind, message); },
          options.recovery_polls),
      alarms_(watch_alarms(name(), channels_, channel_ids_, options_.alarms)) {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("device " + name() + ": " + problem);
  }
  if (channel_ids_.size() != channels_.size()) {
    throw std::invalid_argument("device " + name() + ": channel ids do not match its channels");
  }
}

DevicePoller::Stats DevicePoller::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

DevicePoller::SteadyTime DevicePoller::next_tick_after(SteadyTime now) const {
  const auto elapsed = now - schedule_origin_;
  const std::int64_t tick = elapsed / options_.period + 1;
  return schedule_origin_ + tick * options_.period;
}

// On schedule while the device works; while it fails, the first tick after
// the backoff, so retries stay on the poll grid.
DevicePoller::SteadyTime DevicePoller::next_attempt(bool poll_ok) const {
  const auto wait = poll_ok ? std::chrono::nanoseconds::zero() : connection_.backoff() - std::chrono::nanoseconds(1);
  return next_tick_after(std::chrono::steady_clock::now() + wait);
}

bool DevicePoller::ensure_connected() {
  if (stats().connected) return true;
  const bool connected = connection_.connect([this] { source_->connect(); }, source_->device_info().address);
  std::lock_guard lock(stats_mutex_);
  if (!connected) {
    ++stats_.connect_failures;
    return false;
  }
  stats_.connected = true;
  return true;
}

void DevicePoller::note_failure(const DeviceError& failure, std::int64_t t_ns) {
  if (!failure.link_alive()) {
    source_->disconnect();  // the next attempt starts from a fresh connection
    std::lock_guard lock(stats_mutex_);
    stats_.connected = false;
  }
  connection_.failed(failure.link_alive() ? "bad-reply" : "disconnect", failure.what(), t_ns);
}

bool DevicePoller::poll_once() {
  const std::int64_t request_ns = utc_now_ns();
  std::vector<ChannelReading> readings;
  std::optional<DeviceError> failure;
  try {
    readings = source_->read();
  } catch (const DeviceError& e) {
    failure = e;
  }
  const std::int64_t reply_ns = utc_now_ns();
  const std::int64_t t_ns = request_ns + (reply_ns - request_ns) / 2;
  if (!failure && readings.size() != channel_ids_.size()) {
    failure = DeviceError("device returned " + std::to_string(readings.size()) + " readings for " +
                              std::to_string(channel_ids_.size()) + " channels",
                          storage::SampleStatus::kBadReply);
  }
  std::vector<storage::Sample> samples(channel_ids_.size());
  for (std::size_t i = 0; i < channel_ids_.size(); ++i) {
    samples[i].channel_id = channel_ids_[i];
    samples[i].t_ns = t_ns;
    if (failure) {
      samples[i].status = failure->status();
      samples[i].raw = failure->raw();
    } else {
      samples[i].value = readings[i].value;
      samples[i].raw = readings[i].raw;
      samples[i].status = readings[i].status;
    }
  }
  push(samples);
  for (const storage::Sample& s : samples) report_alarms(alarms_.add_sample(s.channel_id, s.t_ns, s.status, s.value));
  const auto recovery = failure ? ConnectionKeeper::Recovery::kNone : connection_.succeeded();
  if (failure) note_failure(*failure, t_ns);
  {
    std::lock_guard lock(stats_mutex_);
    stats_.last_samples = std::move(samples);
    ++(failure ? stats_.polls_failed : stats_.polls_ok);
  }
  count_recovery(recovery);
  return !failure;
}

void DevicePoller::count_recovery(ConnectionKeeper::Recovery recovery) {
  using Recovery = ConnectionKeeper::Recovery;
  if (recovery != Recovery::kReconnected && recovery != Recovery::kRecovered) return;  // not after a first connect
  std::lock_guard lock(stats_mutex_);
  ++stats_.reconnects;
}

void DevicePoller::count_missed_ticks(SteadyTime deadline, SteadyTime next) {
  const bool deadline_on_schedule = (deadline - schedule_origin_) % options_.period == std::chrono::nanoseconds(0);
  const std::int64_t skipped = (next - deadline) / options_.period - 1;
  if (!deadline_on_schedule || skipped <= 0) return;
  skipped_unreported_ += skipped;
  std::lock_guard lock(stats_mutex_);
  stats_.missed_ticks += skipped;
}

// Stats are this process's; the events put skipped polls in the run, where
// another process (the live page) and a later reader see them.
void DevicePoller::report_skipped(bool at_stop) {
  if (skipped_unreported_ == 0) return;
  const SteadyTime now = std::chrono::steady_clock::now();
  if (!at_stop && last_skipped_event_ && now - *last_skipped_event_ < options_.skipped_event_interval) return;
  record_event("skipped", std::to_string(skipped_unreported_) + " polls skipped (device too slow)");
  skipped_unreported_ = 0;
  last_skipped_event_ = now;
}

bool DevicePoller::poll_count_reached() const {
  const Stats now = stats();
  return options_.poll_count && now.polls_ok + now.polls_failed >= *options_.poll_count;
}

void DevicePoller::loop() {
  poll_until_done();
  count_recovery(connection_.settle());
  report_skipped(true);
}

void DevicePoller::report_alarms(const std::vector<AlarmTransition>& transitions) {
  for (const AlarmTransition& t : transitions) {
    // The callback's owner may be gone once the poller is abandoned.
    if (store_event(t.event_kind(), t.message) && options_.on_alarm) options_.on_alarm(name() + ": " + t.message);
  }
}

bool DevicePoller::wait_watching(SteadyTime deadline) {
  for (;;) {
    const SteadyTime wake =
        alarms_.empty() ? deadline : std::min(deadline, std::chrono::steady_clock::now() + kStaleCheckInterval);
    if (!wait_until(wake)) return false;
    report_alarms(alarms_.check_stale(utc_now_ns()));
    if (wake == deadline) return true;
  }
}

void DevicePoller::poll_until_done() {
  SteadyTime deadline = std::max(schedule_origin_, std::chrono::steady_clock::now());
  while (wait_watching(deadline)) {
    report_skipped(false);
    for (const std::string& notice : source_->take_notices()) record_event("hotplug", notice);
    if (!ensure_connected()) {
      deadline = std::chrono::steady_clock::now() + connection_.backoff();
      continue;
    }
    const bool ok = poll_once();
    if (poll_count_reached()) {
      count_recovery(connection_.settle());
      record_event("stopped", "poll count reached");
      return;
    }
    const SteadyTime next = next_attempt(ok);
    if (ok) count_missed_ticks(deadline, next);
    deadline = next;
  }
}

void DevicePoller::disconnect_device() noexcept { source_->disconnect(); }

}  // namespace bosfuse::acquisition
