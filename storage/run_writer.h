#pragma once
// RunWriter is the one writer of a run: device threads push samples and
// events from anywhere, and a single background thread commits them to the
// RunStore in batches (one transaction per batch, every flush interval or
// when a batch fills). Batching is what makes hundreds of thousands of
// samples per second possible with SQLite; one writer is what keeps device
// threads from ever waiting on a database lock. With every commit (and once
// a second when idle) the writer marks the run alive, so a run whose logger
// was killed can say what is missing.
//
// A store that cannot be written (disk full, I/O error, another connection
// holding the write lock past its timeout) is an outage, counted, never
// thrown: it becomes a `store-full`, `store-io-error`, `store-locked` or
// `store-error` event and one warning when it starts, a `store-recovered`
// event and warning when it ends, and the commit is retried with an
// exponential backoff that costs no CPU meanwhile. Records wait in memory up
// to a stated bound (RunWriterOptions::max_queued_bytes); beyond it they are dropped
// and counted. A stop is bounded in time whatever the store does
// (RunWriterOptions::stop_timeout): what cannot be committed by then is counted in
// Stats and in a `records-lost` event, and close_run() marks the run
// `interrupted`. On a full disk the stop first deletes the run's
// SpaceReserve, so that event and the status still fit.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "storage/database.h"
#include "storage/records.h"
#include "storage/run_store.h"
#include "storage/space_reserve.h"

namespace bosfuse::storage {

// What a RunWriter is set up with.
struct RunWriterOptions {
  // The longest a pushed record waits to be committed: what a kill -9 can
  // lose. WAL with synchronous=NORMAL keeps frequent commits cheap.
  std::chrono::milliseconds flush_interval{50};
  std::size_t max_batch_samples = 100'000;
  // After a failed commit the next try waits retry_initial, doubling at
  // each failure up to retry_max.
  std::chrono::milliseconds retry_initial{100};
  std::chrono::milliseconds retry_max{2'000};
  // Records waiting for a store that cannot be written are kept up to this
  // much memory (about 70 bytes a sample: 64 MiB is a million samples,
  // hours of a typical run); beyond it new records are dropped, counted.
  std::size_t max_queued_bytes = 64u << 20;
  // How long a stop goes on committing against a failing store (waits for
  // another connection's lock included); the run's status gets one second
  // more (kStatusLockWait).
  std::chrono::milliseconds stop_timeout{3'000};
  // The size of the run's SpaceReserve; 0: none.
  std::size_t reserve_bytes = 256u << 10;
  // One line when an outage starts, changes and ends, from the writer's
  // thread; unset: a spdlog warning.
  std::function<void(const std::string&)> on_fault{};
  std::string Validate() const;  // empty when valid, else what is wrong
};

class RunWriter {
 public:
  // What the writer commits into: the run's RunStore, or in a test a store
  // that fails on demand. Each write is one transaction and throws
  // StorageError (its kind() says what failed) without writing anything.
  class Sink {
   public:
    virtual ~Sink() = default;
    virtual void write_events(std::span<const Event> events) = 0;
    virtual void write_frames(std::span<const FrameRecord> frames) = 0;
    virtual void write_samples(std::span<const Sample> samples) = 0;
    virtual void mark_alive(std::int64_t t_ns) = 0;
    virtual void finish(RunStatus status, std::int64_t ended_ns) = 0;
    // Called from the thread that stops the writer (see RunStore).
    virtual void give_up_lock_waits_at(std::chrono::steady_clock::time_point deadline) = 0;
    virtual std::filesystem::path dir() const = 0;  // the run folder (its reserve)
  };


  static constexpr std::chrono::milliseconds kStatusLockWait{1'000};

  struct Stats {
    std::int64_t samples_committed = 0;
    std::int64_t events_committed = 0;
    std::int64_t frames_committed = 0;
    std::int64_t batches_committed = 0;
    std::int64_t failed_commits = 0;
    std::int64_t outages = 0;               // storage faults, each once however many retries it took
    std::int64_t dropped_queue_full = 0;    // records dropped beyond max_queued_bytes
    std::int64_t uncommitted_at_stop = 0;   // records left uncommitted at the stop, or pushed after it
    std::int64_t samples_lost = 0;          // of the two above, the samples
    bool reserve_released = false;          // the stop found the disk full and spent the reserve
    bool status_written = false;            // close_run() stored the run's final status
    std::string status_error;               // why it could not, if it could not
    std::string last_error;                 // in words: what the store last refused, and why
    // Records read that the run does not hold.
    std::int64_t lost() const { return dropped_queue_full + uncommitted_at_stop; }
  };

  // `store` must outlive the writer and not be used by anyone else meanwhile.
  RunWriter(RunStore& store, RunWriterOptions options);
  explicit RunWriter(RunStore& store) : RunWriter(store, RunWriterOptions{}) {}
  RunWriter(Sink& sink, RunWriterOptions options);
  ~RunWriter();  // stops and commits what is queued; never throws
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  void push(const Sample& sample);
  void push(std::span<const Sample> samples);
  void push(const Event& event);
  void push(const FrameRecord& frame);  // the image file must already be in place

  // Blocks until everything pushed before the call is committed (or a commit
  // failed; see stats()).
  void flush();
  // Commits what is queued, within stop_timeout, and ends the writer thread.
  void stop();
  // stop(), then the run's status: complete if nothing was lost, else
  // interrupted; Stats::status_written says whether it could be stored
  // (if not, the next command that opens the run marks it interrupted).
  // Never throws.
  void close_run(std::int64_t ended_ns) noexcept;
  Stats stats() const;

 private:
  // A store that has been failing, since when, and when to try it again.
  struct Outage {
    StorageError::Kind kind = StorageError::Kind::kOther;
    std::chrono::steady_clock::time_point since;  // the first failed try began
    std::chrono::milliseconds retry_delay{0};
    std::chrono::steady_clock::time_point next_retry;
  };
  // Records being dropped because the queue is full, until a commit empties it.
  struct Dropping {
    std::int64_t count = 0;
    std::int64_t since_ns = 0;
    bool said = false;
  };

  void start();
  void run();
  void wait_for_work(std::unique_lock<std::mutex>& lock);
  void commit_before_end(std::unique_lock<std::mutex>& lock);
  void give_up_on_the_rest(std::unique_lock<std::mutex>& lock);
  std::optional<std::pair<StorageError::Kind, std::string>> write_status(RunStatus status,
                                                                         std::int64_t ended_ns) noexcept;
  bool commit_pending(std::unique_lock<std::mutex>& lock);
  void note_failure(const std::exception& error, std::chrono::steady_clock::time_point attempt_started,
                    std::unique_lock<std::mutex>& lock);
  void note_recovery(std::unique_lock<std::mutex>& lock);
  void say_drops(std::unique_lock<std::mutex>& lock);
  void say(std::unique_lock<std::mutex>& lock, std::int64_t t_ns, const std::string& kind, const std::string& message);
  void warn(std::unique_lock<std::mutex>& lock, const std::string& message);
  void mark_alive(std::unique_lock<std::mutex>& lock);
  bool refuse_after_end(std::size_t count, std::size_t samples);
  bool admit(std::size_t count, std::size_t bytes, std::size_t samples);
  std::string what_happens_meanwhile() const;

  std::unique_ptr<Sink> owned_sink_;  // the adapter over a RunStore
  Sink* sink_;
  RunWriterOptions options_;
  std::optional<SpaceReserve> reserve_;
  mutable std::mutex mutex_;
  std::condition_variable wake_writer_;
  std::condition_variable committed_;
  std::vector<Sample> pending_samples_;
  std::vector<Event> pending_events_;
  std::vector<FrameRecord> pending_frames_;
  std::size_t queued_bytes_ = 0;
  std::uint64_t pushed_generation_ = 0;
  std::uint64_t committed_generation_ = 0;
  bool stopping_ = false;
  bool writer_done_ = false;
  std::chrono::steady_clock::time_point stop_deadline_;
  bool committed_since_alive_ = true;
  std::chrono::system_clock::time_point last_alive_;
  std::optional<Outage> outage_;      // touched by the writer thread only
  std::optional<Dropping> dropping_;
  Stats stats_;
  std::thread thread_;
};

}  // namespace bosfuse::storage
