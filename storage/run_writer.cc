#include "storage/run_writer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <stdexcept>

#include "storage/experiment_clock.h"
#include "storage/disk_space.h"

namespace bosfuse::storage {
namespace {

using Kind = StorageError::Kind;
using SteadyClock = std::chrono::steady_clock;

class StoreSink final : public RunWriter::Sink {
 public:
  explicit StoreSink(RunStore& store) : store_(store) {}
  void write_events(std::span<const Event> events) override { store_.write_events(events); }
  void write_frames(std::span<const FrameRecord> frames) override { store_.write_frames(frames); }
  void write_samples(std::span<const Sample> samples) override { store_.write_samples(samples); }
  void mark_alive(std::int64_t t_ns) override { store_.mark_alive(t_ns); }
  void finish(RunStatus status, std::int64_t ended_ns) override { store_.finish(status, ended_ns); }
  void give_up_lock_waits_at(SteadyClock::time_point deadline) override { store_.give_up_lock_waits_at(deadline); }
  std::filesystem::path dir() const override { return store_.dir(); }

 private:
  RunStore& store_;
};

// What a queued record costs in memory, for the queue's bound.
std::size_t bytes_of(const Sample&) { return sizeof(Sample); }
std::size_t bytes_of(const Event& e) { return sizeof(Event) + e.kind.size() + e.message.size(); }
std::size_t bytes_of(const FrameRecord& f) { return sizeof(FrameRecord) + f.path.size(); }
template <typename T>
std::size_t bytes_of(const std::vector<T>& records) {
  std::size_t bytes = 0;
  for (const T& r : records) bytes += bytes_of(r);
  return bytes;
}

std::string event_kind(Kind kind) {
  switch (kind) {
    case Kind::kDiskFull:
      return "store-full";
    case Kind::kIoError:
      return "store-io-error";
    case Kind::kLocked:
      return "store-locked";
    case Kind::kOther:
      break;
  }
  return "store-error";
}

std::string seconds_text(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", seconds);
  return text;
}

// The failure in words. SQLite's own message for the faults a user can
// act on, the whole of it (with the statement) for anything else.
// `locked_for`: since the first try that found the lock held.
std::pair<Kind, std::string> describe(const std::exception& error, std::chrono::duration<double> locked_for) {
  const auto* storage = dynamic_cast<const StorageError*>(&error);
  const Kind kind = storage ? storage->kind() : Kind::kOther;
  const std::string reason = storage && !storage->reason().empty() ? storage->reason() : error.what();
  switch (kind) {
    case Kind::kDiskFull:
      return {kind, "the disk holding the run is full (" + reason + ")"};
    case Kind::kIoError:
      return {kind, "the run store cannot be written: the file system reports an I/O error (" + reason + ")"};
    case Kind::kLocked:
      return {kind, "another connection has held the run store's write lock for " + seconds_text(locked_for.count()) +
                        " (" + reason + ")"};
    case Kind::kOther:
      break;
  }
  return {kind, std::string("a commit to the run store failed: ") + error.what()};
}

// Puts `taken` back in front of what was pushed meanwhile.
template <typename T>
void requeue(std::vector<T>& taken, std::vector<T>& pending) {
  taken.insert(taken.end(), pending.begin(), pending.end());
  pending.swap(taken);
}

}  // namespace

std::string RunWriterOptions::Validate() const {
  if (flush_interval.count() <= 0) return "flush_interval must be positive";
  if (max_batch_samples == 0) return "max_batch_samples must be positive";
  if (retry_initial.count() <= 0) return "retry_initial must be positive";
  if (retry_max < retry_initial) return "retry_max must be at least retry_initial";
  if (max_queued_bytes == 0) return "max_queued_bytes must be positive";
  if (stop_timeout.count() < 0) return "stop_timeout must not be negative";
  return {};
}

RunWriter::RunWriter(RunStore& store, RunWriterOptions options)
    : owned_sink_(std::make_unique<StoreSink>(store)), sink_(owned_sink_.get()), options_(std::move(options)) {
  start();
}

RunWriter::RunWriter(Sink& sink, RunWriterOptions options) : sink_(&sink), options_(std::move(options)) { start(); }

void RunWriter::start() {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("RunWriter options: " + problem);
  }
  if (!options_.on_fault) options_.on_fault = [](const std::string& line) { spdlog::warn("{}", line); };
  if (options_.reserve_bytes > 0) {
    try {
      reserve_.emplace(sink_->dir(), options_.reserve_bytes);
    } catch (const std::exception& e) {
      options_.on_fault(std::string(e.what()) + "; should the disk fill up, the run may not be able to say so");
    }
  }
  thread_ = std::thread([this] { run(); });
}

RunWriter::~RunWriter() {
  try {
    stop();
  } catch (...) {
    // Destructors never throw; stop() only throws if the thread cannot join.
  }
}

void RunWriter::push(const Sample& sample) { push(std::span<const Sample>(&sample, 1)); }

// Records that arrive after the writer ended cannot be stored; they are
// counted so the run says it is incomplete.
bool RunWriter::refuse_after_end(std::size_t count, std::size_t samples) {
  if (!writer_done_) return false;
  stats_.uncommitted_at_stop += static_cast<std::int64_t>(count);
  stats_.samples_lost += static_cast<std::int64_t>(samples);
  stats_.last_error = "records arrived after the writer had stopped";
  return true;
}

// The queue's bound: a record that does not fit is dropped and counted,
// and the writer thread says so.
bool RunWriter::admit(std::size_t count, std::size_t bytes, std::size_t samples) {
  if (queued_bytes_ + bytes <= options_.max_queued_bytes) {
    queued_bytes_ += bytes;
    return true;
  }
  stats_.dropped_queue_full += static_cast<std::int64_t>(count);
  stats_.samples_lost += static_cast<std::int64_t>(samples);
  if (!dropping_) dropping_ = Dropping{0, utc_now_ns(), false};
  dropping_->count += static_cast<std::int64_t>(count);
  return false;
}

void RunWriter::push(std::span<const Sample> samples) {
  bool full = false;
  {
    std::lock_guard lock(mutex_);
    const std::size_t n = samples.size();
    if (refuse_after_end(n, n) || !admit(n, n * sizeof(Sample), n)) return;
    pending_samples_.insert(pending_samples_.end(), samples.begin(), samples.end());
    ++pushed_generation_;
    full = pending_samples_.size() >= options_.max_batch_samples;
  }
  if (full) wake_writer_.notify_one();
}

void RunWriter::push(const Event& event) {
  std::lock_guard lock(mutex_);
  if (refuse_after_end(1, 0) || !admit(1, bytes_of(event), 0)) return;
  pending_events_.push_back(event);
  ++pushed_generation_;
}

void RunWriter::push(const FrameRecord& frame) {
  std::lock_guard lock(mutex_);
  if (refuse_after_end(1, 0) || !admit(1, bytes_of(frame), 0)) return;
  pending_frames_.push_back(frame);
  ++pushed_generation_;
}

void RunWriter::flush() {
  std::unique_lock lock(mutex_);
  const std::uint64_t target = pushed_generation_;
  wake_writer_.notify_one();
  const std::int64_t failures_before = stats_.failed_commits;
  committed_.wait(
      lock, [&] { return committed_generation_ >= target || stats_.failed_commits > failures_before || writer_done_; });
}

void RunWriter::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
    stop_deadline_ = SteadyClock::now() + options_.stop_timeout;
  }
  // A commit waiting for another connection's lock gives up at the deadline.
  sink_->give_up_lock_waits_at(stop_deadline_);
  wake_writer_.notify_one();
  if (thread_.joinable()) thread_.join();
  sink_->give_up_lock_waits_at(SteadyClock::time_point::max());
}

void RunWriter::close_run(std::int64_t ended_ns) noexcept {
  try {
    stop();
  } catch (...) {
    // Only a thread that cannot join; the status is still worth a try.
  }
  std::unique_lock lock(mutex_);
  const RunStatus status = stats_.lost() == 0 ? RunStatus::kComplete : RunStatus::kInterrupted;
  lock.unlock();
  auto failure = write_status(status, ended_ns);
  // A disk that filled with the last commit: the reserve's room is for this.
  if (failure && failure->first == Kind::kDiskFull && reserve_ && reserve_->release()) {
    lock.lock();
    stats_.reserve_released = true;
    lock.unlock();
    failure = write_status(status, ended_ns);
  }
  lock.lock();
  stats_.status_written = !failure;
  stats_.status_error = failure ? failure->second : std::string();
  reserve_.reset();  // the run is closed: its room is the disk's again
}

// The run's status, with a lock wait of its own (the stop's deadline may
// have passed); what failed, if it did.
std::optional<std::pair<StorageError::Kind, std::string>> RunWriter::write_status(RunStatus status,
                                                                                  std::int64_t ended_ns) noexcept {
  std::optional<std::pair<Kind, std::string>> failure;
  const auto attempt_started = SteadyClock::now();
  try {
    sink_->give_up_lock_waits_at(attempt_started + kStatusLockWait);
    sink_->finish(status, ended_ns);
  } catch (const std::exception& e) {
    failure = describe(e, SteadyClock::now() - (outage_ ? outage_->since : attempt_started));
  } catch (...) {
    failure = std::make_pair(Kind::kOther, std::string("unknown error"));
  }
  try {
    sink_->give_up_lock_waits_at(SteadyClock::time_point::max());
  } catch (...) {
  }
  return failure;
}

RunWriter::Stats RunWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void RunWriter::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wait_for_work(lock);
    if (stopping_) break;
    if (commit_pending(lock)) mark_alive(lock);
    say_drops(lock);
  }
  commit_before_end(lock);
  give_up_on_the_rest(lock);
  writer_done_ = true;
  committed_.notify_all();
}

// During an outage only the next retry (or the stop) wakes the writer, so
// a store that cannot be written costs no CPU however fast records come.
void RunWriter::wait_for_work(std::unique_lock<std::mutex>& lock) {
  if (outage_) {
    wake_writer_.wait_until(lock, outage_->next_retry, [&] { return stopping_; });
    return;
  }
  wake_writer_.wait_for(lock, options_.flush_interval, [&] {
    return stopping_ || pending_samples_.size() >= options_.max_batch_samples ||
           committed_generation_ < pushed_generation_;
  });
}

// What arrived while the last commit ran is committed too before the end;
// a store that keeps failing is tried until the stop's deadline, a full
// disk only once (it does not empty itself in the seconds a stop has).
void RunWriter::commit_before_end(std::unique_lock<std::mutex>& lock) {
  for (;;) {
    const bool committed = commit_pending(lock);
    if (committed) mark_alive(lock);
    if (pushed_generation_ == committed_generation_) return;
    if (committed) continue;
    if (outage_ && outage_->kind == Kind::kDiskFull) return;
    const auto now = SteadyClock::now();
    if (now >= stop_deadline_) return;
    wake_writer_.wait_until(lock, std::min(stop_deadline_, now + options_.retry_initial));
  }
}

// The stop's deadline has passed with records uncommitted: they are
// counted, and the run's events get one last try with a `records-lost`
// event saying how many — in the room of the reserve if the disk is full.
void RunWriter::give_up_on_the_rest(std::unique_lock<std::mutex>& lock) {
  const std::size_t samples = pending_samples_.size();
  const std::size_t frames = pending_frames_.size();
  if (samples + frames + pending_events_.size() == 0) return;
  stats_.uncommitted_at_stop += static_cast<std::int64_t>(samples + frames);
  stats_.samples_lost += static_cast<std::int64_t>(samples);
  pending_samples_.clear();
  pending_frames_.clear();
  std::vector<Event> events;
  events.swap(pending_events_);
  const bool account = samples + frames > 0;
  if (account) {
    std::string message =
        std::to_string(samples) + " samples and " + std::to_string(frames) + " frames read were never stored";
    if (stats_.dropped_queue_full > 0) {
      message += ", besides " + std::to_string(stats_.dropped_queue_full) + " dropped while the queue was full";
    }
    events.push_back(Event{0, std::nullopt, utc_now_ns(), "records-lost", message + ": " + stats_.last_error});
  }
  if (outage_ && outage_->kind == Kind::kDiskFull && reserve_ && reserve_->release()) stats_.reserve_released = true;
  lock.unlock();
  bool stored = false;
  try {
    sink_->write_events(events);
    stored = true;
  } catch (const std::exception&) {
    // Counted below; the summary says what the run cannot.
  }
  lock.lock();
  if (stored) {
    stats_.events_committed += static_cast<std::int64_t>(events.size());
  } else {
    // All but the writer's own account of the loss.
    stats_.uncommitted_at_stop += static_cast<std::int64_t>(events.size() - (account ? 1 : 0));
  }
  queued_bytes_ = 0;
  committed_generation_ = pushed_generation_;
}

// The run's last sign of life, so a run whose logger died can say how much
// is missing: with every commit, and at least once a second when idle.
void RunWriter::mark_alive(std::unique_lock<std::mutex>& lock) {
  const auto now = std::chrono::system_clock::now();
  if (!committed_since_alive_ && now - last_alive_ < std::chrono::seconds(1)) return;
  committed_since_alive_ = false;
  last_alive_ = now;
  lock.unlock();
  try {
    sink_->mark_alive(std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count());
  } catch (const std::exception&) {
    // A missed heartbeat costs only precision in an interrupted run's account.
  }
  lock.lock();
}

// Takes what is pending, commits it without holding the lock, and puts back
// at the front of the queue whatever a failed commit left unwritten. Each
// kind is its own transaction, cleared once committed so a later failure
// never writes it twice.
bool RunWriter::commit_pending(std::unique_lock<std::mutex>& lock) {
  if (committed_generation_ == pushed_generation_) return true;
  std::vector<Sample> samples;
  std::vector<Event> events;
  std::vector<FrameRecord> frames;
  samples.swap(pending_samples_);
  events.swap(pending_events_);
  frames.swap(pending_frames_);
  const std::uint64_t generation = pushed_generation_;
  const std::size_t taken_bytes = queued_bytes_;
  const auto event_count = static_cast<std::int64_t>(events.size());
  const auto frame_count = static_cast<std::int64_t>(frames.size());
  const auto attempt_started = SteadyClock::now();
  lock.unlock();
  std::exception_ptr failure;
  try {
    sink_->write_events(events);
    events.clear();
    sink_->write_frames(frames);
    frames.clear();
    sink_->write_samples(samples);
  } catch (...) {
    failure = std::current_exception();
  }
  lock.lock();
  stats_.events_committed += event_count - static_cast<std::int64_t>(events.size());
  stats_.frames_committed += frame_count - static_cast<std::int64_t>(frames.size());
  if (failure) {
    ++stats_.failed_commits;
    queued_bytes_ -= taken_bytes - (bytes_of(samples) + bytes_of(events) + bytes_of(frames));
    requeue(samples, pending_samples_);
    requeue(events, pending_events_);
    requeue(frames, pending_frames_);
    try {
      std::rethrow_exception(failure);
    } catch (const std::exception& e) {
      note_failure(e, attempt_started, lock);
    } catch (...) {
      note_failure(std::runtime_error("unknown error"), attempt_started, lock);
    }
    committed_.notify_all();
    return false;
  }
  queued_bytes_ -= taken_bytes;
  stats_.samples_committed += static_cast<std::int64_t>(samples.size());
  ++stats_.batches_committed;
  committed_since_alive_ = true;
  committed_generation_ = generation;
  if (outage_) note_recovery(lock);
  if (dropping_) {
    const Dropping dropped = *dropping_;
    dropping_.reset();
    say(lock, dropped.since_ns, "records-dropped",
        std::to_string(dropped.count) + " records were dropped because the store could not take them and the " +
            bytes_text(options_.max_queued_bytes) + " allowed for records waiting for it were full");
  }
  committed_.notify_all();
  return true;
}

std::string RunWriter::what_happens_meanwhile() const {
  return "records wait in memory (up to " + bytes_text(options_.max_queued_bytes) +
         ", then they are dropped and counted) and the commit is retried, at most every " +
         seconds_text(std::chrono::duration<double>(options_.retry_max).count());
}

// An outage is said when it starts and when its nature changes, never per
// retry; the retries back off.
void RunWriter::note_failure(const std::exception& error, std::chrono::steady_clock::time_point attempt_started,
                             std::unique_lock<std::mutex>& lock) {
  const auto now = SteadyClock::now();
  const auto [kind, description] = describe(error, now - (outage_ ? outage_->since : attempt_started));
  stats_.last_error = description;
  if (!outage_) {
    outage_ = Outage{kind, attempt_started, options_.retry_initial, now + options_.retry_initial};
    ++stats_.outages;
    say(lock, utc_now_ns(), event_kind(kind), description + "; " + what_happens_meanwhile());
    return;
  }
  outage_->retry_delay = std::min(outage_->retry_delay * 2, options_.retry_max);
  outage_->next_retry = now + outage_->retry_delay;
  if (kind != outage_->kind) {
    outage_->kind = kind;
    say(lock, utc_now_ns(), event_kind(kind), description + "; " + what_happens_meanwhile());
  }
}

void RunWriter::note_recovery(std::unique_lock<std::mutex>& lock) {
  const double seconds = std::chrono::duration<double>(SteadyClock::now() - outage_->since).count();
  const std::string was = event_kind(outage_->kind);
  outage_.reset();
  say(lock, utc_now_ns(), "store-recovered",
      "the run store is written again after " + seconds_text(seconds) + " (" + was + ")");
}

void RunWriter::say_drops(std::unique_lock<std::mutex>& lock) {
  if (!dropping_ || dropping_->said) return;
  dropping_->said = true;
  warn(lock, "the " + bytes_text(options_.max_queued_bytes) +
                 " allowed for records waiting for the store are full: new records are dropped, and counted, "
                 "until the store takes them again");
}

// An event of the writer's own (never refused by the queue's bound), and
// the same line as a warning.
void RunWriter::say(std::unique_lock<std::mutex>& lock, std::int64_t t_ns, const std::string& kind,
                    const std::string& message) {
  Event event{0, std::nullopt, t_ns, kind, message};
  queued_bytes_ += bytes_of(event);
  pending_events_.push_back(std::move(event));
  ++pushed_generation_;
  warn(lock, message);
}

void RunWriter::warn(std::unique_lock<std::mutex>& lock, const std::string& message) {
  const std::string line = sink_->dir().string() + ": " + message;
  lock.unlock();  // the callback may push (an event of the caller's own)
  try {
    options_.on_fault(line);
  } catch (...) {
    // A warning that cannot be shown must not stop the writer.
  }
  lock.lock();
}

}  // namespace bosfuse::storage
