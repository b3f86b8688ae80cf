#pragma once
// A RunStore is one experiment run on disk: a folder holding `run.sqlite`
// (schema in docs/SCHEMA.md) and, beside it, the run's frames as image files
// referenced by relative path. It is the only way the rest of bosfuse reads
// or writes a run. Writes of samples go in batches, each batch one
// transaction, so a crash loses at most the batch in flight and never
// corrupts what was committed. A RunStore is one SQLite connection: use it
// from one thread (the logger's writer thread owns the writing one; readers
// open their own).
//
// The store that records a run holds its RunLock. A run found `running`
// with nobody holding the lock lost its logger (killed, crashed, power
// cut): the next open marks it interrupted, ends it at the logger's last
// sign of life, and records an "interrupted" event saying what is missing.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "storage/database.h"
#include "storage/records.h"
#include "storage/run_lock.h"

namespace bosfuse::storage {

struct TimeRange {
  std::int64_t from_ns = INT64_MIN;  // inclusive
  std::int64_t to_ns = INT64_MAX;    // inclusive
};

struct ChannelSummary {
  ChannelInfo channel;
  std::string device_name;
  std::int64_t sample_count = 0;
  std::int64_t ok_count = 0;
  std::optional<std::int64_t> first_ns;
  std::optional<std::int64_t> last_ns;
  std::optional<double> min_value;
  std::optional<double> max_value;
};

class RunStore {
 public:
  static constexpr const char* kDatabaseFileName = "run.sqlite";

  enum class CreateMode {
    kNew,     // refuse a folder that already holds a run
    kAppend,  // continue the run already in the folder (or start one)
  };

  // Creates the run folder if needed and starts (or, with kAppend, resumes) a
  // run, whose status becomes `running`, and holds its RunLock. Refuses a run
  // another logger is recording, and appending with a different experiment
  // file (`info.config_toml`).
  static RunStore create(const std::filesystem::path& run_dir, const RunInfo& info, CreateMode mode);
  // Opens an existing run; throws StorageError if the folder holds none.
  // Closes a run whose logger died first (see above).
  static RunStore open(const std::filesystem::path& run_dir, bool writable = false);
  // Opens an existing run read-only exactly as it is: a run whose logger
  // died stays marked `running` (nothing is written); abandoned() says so.
  static RunStore open_as_found(const std::filesystem::path& run_dir);
  // Marked `running` with nobody holding its RunLock: its logger died.
  static bool abandoned(const std::filesystem::path& run_dir);
  static bool holds_run(const std::filesystem::path& run_dir);

  const std::filesystem::path& dir() const { return dir_; }
  RunInfo run() const;

  // Upserts by name, so an appended run keeps its device and channel ids.
  std::int64_t add_device(const DeviceInfo& device);
  std::int64_t add_channel(const ChannelInfo& channel);

  void write_samples(std::span<const Sample> samples);  // one transaction
  void write_events(std::span<const Event> events);     // one transaction
  std::int64_t add_frame(const FrameRecord& frame);
  void write_frames(std::span<const FrameRecord> frames);  // one transaction
  void finish(RunStatus status, std::int64_t ended_ns);
  // The session was started to run until `t_ns` (a set duration), so an
  // interruption can say how much of it is missing.
  void set_planned_end(std::int64_t t_ns);
  // The logger's heartbeat: it was alive at `t_ns`.
  void mark_alive(std::int64_t t_ns);
  // Waits for another connection's lock end at `deadline` (see Database);
  // the one call that is safe from another thread, so a stop can cut short
  // a wait the writer thread is in.
  void give_up_lock_waits_at(std::chrono::steady_clock::time_point deadline) { db_.give_up_lock_waits_at(deadline); }

  std::vector<DeviceInfo> devices() const;
  std::vector<ChannelInfo> channels() const;
  // One channel's samples in time order, in its index's order where two share
  // an instant (schema.cc, version 7).
  std::vector<Sample> read_samples(std::int64_t channel_id, TimeRange range = {}) const;
  // The same samples as read_samples, time, value and status only: read from
  // the index alone.
  SampleColumns read_sample_columns(std::int64_t channel_id) const;
  // Every sample of the run in time order (ties by channel), streamed so
  // an export of a long run needs no memory for it.
  void for_each_sample(const std::function<void(const Sample&)>& visit, TimeRange range = {}) const;
  std::vector<Event> events(TimeRange range = {}) const;
  std::vector<FrameRecord> frames(TimeRange range = {}) const;
  std::vector<ChannelSummary> channel_summaries() const;
  // The newest t_ns of any sample, frame or event; nothing for an empty run.
  std::optional<std::int64_t> last_record_ns() const;
  // The oldest sample's t_ns, whatever its status; nothing without samples.
  std::optional<std::int64_t> first_sample_ns() const;
  // The first marker event (kind "marker") with this message.
  std::optional<std::int64_t> marker_ns(const std::string& message) const;

 private:
  RunStore(std::filesystem::path dir, Database::Mode mode);
  std::int64_t insert_run(const RunInfo& info);
  void resume(const RunInfo& previous, const RunInfo& info);
  void close_interrupted();
  static void close_if_abandoned(const std::filesystem::path& run_dir);

  std::filesystem::path dir_;
  mutable Database db_;
  std::int64_t run_id_ = 0;
  std::optional<Statement> insert_sample_;
  std::optional<RunLock> lock_;  // held by the store that records the run
};

}  // namespace bosfuse::storage
