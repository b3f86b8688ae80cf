#include "acquisition/device_poller.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::acquisition {
std::string DevicePoller::Options::Validate() const {
  if (period <= std::chrono::nanoseconds::zero()) return "poll period must be positive";
  if (poll_count && *poll_count < 1) return "poll count must be at least 1";
  return ConnectionKeeper::Backoff{backoff_initial, backoff_max}.Validate();
}

DevicePoller::DevicePoller(std::unique_ptr<ThermocoupleSource> source, std::int64_t device_id,
                           std::vector<std::int64_t> channel_ids, storage::RunWriter& writer, Options options)
    : source_(std::move(source)),
      name_(source_->device_info().name),
      device_id_(device_id),
      channel_ids_(std::move(channel_ids)),
      channels_(source_->channel_infos()),
      writer_(writer),
      options_(options),
      connection_({options.backoff_initial, options.backoff_max},
                  [this](const std::string& kind, const std::string& message) { record_event(kind, message); }) {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("device " + name_ + ": " + problem);
  }
  if (channel_ids_.size() != channels_.size()) {
    throw std::invalid_argument("device " + name_ + ": channel ids do not match its channels");
  }
}

DevicePoller::~DevicePoller() { stop(); }

void DevicePoller::start() {
  schedule_origin_ = std::chrono::steady_clock::now();
  thread_ = std::thread([this] { run(); });
}

void DevicePoller::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

DevicePoller::Stats DevicePoller::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

bool DevicePoller::wait_until(SteadyTime deadline) {
  std::unique_lock lock(mutex_);
  return !wake_.wait_until(lock, deadline, [&] { return stopping_; });
}

DevicePoller::SteadyTime DevicePoller::next_tick_after(SteadyTime now) const {
  const auto elapsed = now - schedule_origin_;
  const std::int64_t tick = elapsed / options_.period + 1;
  return schedule_origin_ + tick * options_.period;
}

void DevicePoller::record_event(const std::string& kind, const std::string& message) {
  record_device_event(writer_, device_id_, name_, kind, message);
}

bool DevicePoller::ensure_connected() {
  {
    std::lock_guard lock(mutex_);
    if (stats_.connected) return true;
  }
  const auto outcome = connection_.connect([this] { source_->connect(); }, source_->device_info().address);
  std::lock_guard lock(mutex_);
  if (outcome == ConnectionKeeper::Outcome::kFailed) {
    ++stats_.connect_failures;
    return false;
  }
  stats_.connected = true;
  if (outcome == ConnectionKeeper::Outcome::kReconnected) ++stats_.reconnects;
  return true;
}

std::string DevicePoller::poll_once() {
  const std::int64_t request_ns = utc_now_ns();
  std::vector<ChannelReading> readings;
  std::string failure;
  try {
    readings = source_->read();
  } catch (const DeviceError& e) {
    failure = e.what();
  }
  const std::int64_t reply_ns = utc_now_ns();
  const std::int64_t t_ns = request_ns + (reply_ns - request_ns) / 2;
  if (failure.empty() && readings.size() != channel_ids_.size()) {
    failure = "device returned " + std::to_string(readings.size()) + " readings for " +
              std::to_string(channel_ids_.size()) + " channels";
  }
  std::vector<storage::Sample> samples(channel_ids_.size());
  for (std::size_t i = 0; i < channel_ids_.size(); ++i) {
    samples[i].channel_id = channel_ids_[i];
    samples[i].t_ns = t_ns;
    if (failure.empty()) {
      samples[i].value = readings[i].value;
      samples[i].raw = readings[i].raw;
      samples[i].status = readings[i].status;
    } else {
      samples[i].status = storage::SampleStatus::kTimeout;
    }
  }
  writer_.push(samples);
  std::lock_guard lock(mutex_);
  stats_.last_samples = std::move(samples);
  if (failure.empty()) {
    ++stats_.polls_ok;
  } else {
    ++stats_.polls_failed;
    stats_.connected = false;
    connection_.lost(t_ns);
  }
  return failure;
}

void DevicePoller::count_missed_ticks(SteadyTime deadline, SteadyTime next) {
  const bool deadline_on_schedule = (deadline - schedule_origin_) % options_.period == std::chrono::nanoseconds(0);
  const std::int64_t skipped = (next - deadline) / options_.period - 1;
  if (!deadline_on_schedule || skipped <= 0) return;
  std::lock_guard lock(mutex_);
  stats_.missed_ticks += skipped;
}

void DevicePoller::run() {
  SteadyTime deadline = schedule_origin_;
  while (wait_until(deadline)) {
    for (const std::string& notice : source_->take_notices()) record_event("hotplug", notice);
    if (!ensure_connected()) {
      deadline = std::chrono::steady_clock::now() + connection_.backoff();
      continue;
    }
    if (const std::string failure = poll_once(); !failure.empty()) {
      source_->disconnect();  // the next attempt starts from a fresh connection
      record_event("disconnect", failure);
    }
    if (options_.poll_count && stats().polls_ok + stats().polls_failed >= *options_.poll_count) {
      record_event("stopped", "poll count reached");
      break;
    }
    const SteadyTime next = next_tick_after(std::chrono::steady_clock::now());
    count_missed_ticks(deadline, next);
    deadline = next;
  }
  source_->disconnect();
}

}  // namespace bosfuse::acquisition
