#pragma once
// RunWriter is the one writer of a run: device threads push samples and
// events from anywhere, and a single background thread commits them to the
// RunStore in batches (one transaction per batch, every flush interval or
// when a batch fills). Batching is what makes hundreds of thousands of
// samples per second possible with SQLite; one writer is what keeps device
// threads from ever waiting on a database lock. If a batch cannot be
// committed (disk full, say) it stays queued and is retried, so nothing a
// device delivered is dropped while the writer lives; a stop commits
// everything pushed before it, including what arrived during the last
// commit. With every commit (and once a second when idle) the writer marks
// the run alive, so a run whose logger was killed can say what is missing.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "storage/records.h"
#include "storage/run_store.h"

namespace bosfuse::storage {

class RunWriter {
 public:
  struct Options {
    // The longest a pushed record waits to be committed: what a kill -9 can
    // lose. WAL with synchronous=NORMAL keeps frequent commits cheap.
    std::chrono::milliseconds flush_interval{50};
    std::size_t max_batch_samples = 100'000;
    std::string Validate() const;  // empty when valid, else what is wrong
  };

  struct Stats {
    std::int64_t samples_committed = 0;
    std::int64_t events_committed = 0;
    std::int64_t frames_committed = 0;
    std::int64_t batches_committed = 0;
    std::int64_t failed_commits = 0;
    std::int64_t uncommitted_at_stop = 0;  // samples + events + frames never committed (see last_error)
    std::string last_error;
  };

  // `store` must outlive the writer and not be used by anyone else meanwhile.
  RunWriter(RunStore& store, Options options);
  explicit RunWriter(RunStore& store) : RunWriter(store, Options{}) {}
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
  // Commits what is queued and ends the writer thread.
  void stop();
  Stats stats() const;

 private:
  void run();
  bool commit_pending(std::unique_lock<std::mutex>& lock);
  void mark_alive(std::unique_lock<std::mutex>& lock);
  bool refuse_after_end(std::size_t count);

  RunStore& store_;
  Options options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_writer_;
  std::condition_variable committed_;
  std::vector<Sample> pending_samples_;
  std::vector<Event> pending_events_;
  std::vector<FrameRecord> pending_frames_;
  std::uint64_t pushed_generation_ = 0;
  std::uint64_t committed_generation_ = 0;
  bool stopping_ = false;
  bool writer_done_ = false;
  bool committed_since_alive_ = true;
  std::chrono::system_clock::time_point last_alive_;
  Stats stats_;
  std::thread thread_;
};

}  // namespace bosfuse::storage
