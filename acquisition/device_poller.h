#pragma once
// A DevicePoller reads one ThermocoupleSource on its own thread, on a fixed
// schedule: poll k is due at start + k·period (computed, never accumulated,
// so there is no drift over hours). Each poll's samples are stamped with the
// host UTC clock at the midpoint of request and reply and pushed to the
// RunWriter. A failed poll stores samples with the failure's status (timeout
// when the link broke, bad-reply when the device answered nonsense); the
// outage is recorded once and retried with exponential backoff, and its end
// is recorded with the length of the gap and its failed polls, once the
// device has answered DevicePollerOptions::recovery_polls polls in a row: a device that
// fails every other poll is one outage, not an event pair per poll. Polls skipped because one overran
// are recorded too ("skipped" events), gathered so that a device always too
// slow for its period adds one event per interval, not one per poll. One
// dead device never stalls the others: each has its own thread (a
// DeviceWorker), and the shared writer never blocks on a device.
//
// Channels with alarm limits are watched by an AlarmMonitor on the same
// thread: every sample is judged as it is pushed, and staleness on every
// poll attempt and at least once a second in between, so a device that
// fails, or is waiting out a reconnection backoff, still goes stale on
// time. Each alarm raised or cleared is an "alarm" or "alarm-cleared"
// event and a line to DevicePollerOptions::on_alarm.

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/alarm_monitor.h"
#include "acquisition/connection_keeper.h"
#include "acquisition/device_worker.h"
#include "acquisition/thermocouple_source.h"
#include "storage/run_writer.h"

namespace bosfuse::acquisition {

// What a DevicePoller is set up with.
struct DevicePollerOptions {
  std::chrono::nanoseconds period = std::chrono::seconds(1);
  std::chrono::milliseconds backoff_initial{250};
  std::chrono::milliseconds backoff_max{10'000};
  std::optional<std::int64_t> poll_count;  // stop after this many polls (ok or failed)
  // At most one "skipped" event per interval, with the count since the
  // last; the rest when the poller stops.
  std::chrono::nanoseconds skipped_event_interval = std::chrono::seconds(10);
  // One per channel, in channel_infos() order; empty when none has any.
  std::vector<AlarmLimits> alarms = {};
  // Called on the device's thread with "<device>: <event message>" for
  // each alarm raised or cleared; never once the poller is abandoned.
  std::function<void(const std::string&)> on_alarm = {};
  // Polls in a row that must work before an outage is declared over; a
  // failure among them continues the outage.
  int recovery_polls = 3;
  std::string Validate() const;
};

class DevicePoller : public DeviceWorker {
 public:
  struct Stats {
    std::int64_t polls_ok = 0;
    std::int64_t polls_failed = 0;
    std::int64_t connect_failures = 0;
    std::int64_t reconnects = 0;    // outages that ended after the device had been read
    std::int64_t missed_ticks = 0;  // polls skipped because a poll overran
    bool connected = false;
    std::vector<storage::Sample> last_samples;  // the latest poll, one per channel
  };

  // `channel_ids` are the run store ids of source->channel_infos(), in order.
  // Own it in a std::shared_ptr (std::make_shared) before start().
  DevicePoller(std::unique_ptr<ThermocoupleSource> source, std::int64_t device_id,
               std::vector<std::int64_t> channel_ids, storage::RunWriter& writer, DevicePollerOptions options);

  Stats stats() const;
  const std::vector<storage::ChannelInfo>& channels() const { return channels_; }

 private:
  void loop() override;
  void poll_until_done();
  bool wait_watching(SteadyTime deadline);
  void report_alarms(const std::vector<AlarmTransition>& transitions);
  void disconnect_device() noexcept override;
  bool ensure_connected();
  bool poll_once();  // false when the device failed
  void note_failure(const DeviceError& failure, std::int64_t t_ns);
  void count_missed_ticks(SteadyTime deadline, SteadyTime next);
  void report_skipped(bool at_stop);
  SteadyTime next_tick_after(SteadyTime now) const;
  SteadyTime next_attempt(bool poll_ok) const;
  bool poll_count_reached() const;
  void count_recovery(ConnectionKeeper::Recovery recovery);

  std::unique_ptr<ThermocoupleSource> source_;
  std::vector<std::int64_t> channel_ids_;
  std::vector<storage::ChannelInfo> channels_;
  DevicePollerOptions options_;
  SteadyTime schedule_origin_;
  ConnectionKeeper connection_;  // used on the worker thread only
  std::int64_t skipped_unreported_ = 0;  // worker thread only, like the next two
  std::optional<SteadyTime> last_skipped_event_;
  AlarmMonitor alarms_;

  mutable std::mutex stats_mutex_;
  Stats stats_;
};

}  // namespace bosfuse::acquisition
