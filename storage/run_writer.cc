#include "storage/run_writer.h"

#include <exception>
#include <stdexcept>

namespace bosfuse::storage {

std::string RunWriter::Options::Validate() const {
  if (flush_interval.count() <= 0) return "flush_interval must be positive";
  if (max_batch_samples == 0) return "max_batch_samples must be positive";
  return {};
}

RunWriter::RunWriter(RunStore& store, Options options) : store_(store), options_(options) {
  if (const std::string problem = options_.Validate(); !problem.empty()) {
    throw std::invalid_argument("RunWriter options: " + problem);
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
bool RunWriter::refuse_after_end(std::size_t count) {
  if (!writer_done_) return false;
  stats_.uncommitted_at_stop += static_cast<std::int64_t>(count);
  stats_.last_error = "records arrived after the writer had stopped";
  return true;
}

void RunWriter::push(std::span<const Sample> samples) {
  bool full = false;
  {
    std::lock_guard lock(mutex_);
    if (refuse_after_end(samples.size())) return;
    pending_samples_.insert(pending_samples_.end(), samples.begin(), samples.end());
    ++pushed_generation_;
    full = pending_samples_.size() >= options_.max_batch_samples;
  }
  if (full) wake_writer_.notify_one();
}

void RunWriter::push(const Event& event) {
  std::lock_guard lock(mutex_);
  if (refuse_after_end(1)) return;
  pending_events_.push_back(event);
  ++pushed_generation_;
}

void RunWriter::push(const FrameRecord& frame) {
  std::lock_guard lock(mutex_);
  if (refuse_after_end(1)) return;
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
  }
  wake_writer_.notify_one();
  if (thread_.joinable()) thread_.join();
}

RunWriter::Stats RunWriter::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void RunWriter::run() {
  static constexpr int kShutdownRetries = 5;
  int failures_while_stopping = 0;
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_writer_.wait_for(lock, options_.flush_interval, [&] {
      return stopping_ || pending_samples_.size() >= options_.max_batch_samples ||
             committed_generation_ < pushed_generation_;
    });
    const bool committed = commit_pending(lock);
    if (committed) mark_alive(lock);
    if (!stopping_) continue;
    // What arrived while the last commit ran is committed too before the end.
    if (pushed_generation_ == committed_generation_) break;
    if (committed) continue;
    // A store that keeps failing at shutdown: a few more tries, then give
    // up loudly (stats().last_error says why).
    if (++failures_while_stopping > kShutdownRetries) break;
    lock.unlock();
    std::this_thread::sleep_for(options_.flush_interval);
    lock.lock();
  }
  stats_.uncommitted_at_stop +=
      static_cast<std::int64_t>(pending_samples_.size() + pending_events_.size() + pending_frames_.size());
  writer_done_ = true;
  committed_.notify_all();
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
    store_.mark_alive(std::chrono::duration_cast<std::chrono::nanoseconds>(now.time_since_epoch()).count());
  } catch (const std::exception&) {
    // A missed heartbeat costs only precision in an interrupted run's account.
  }
  lock.lock();
}

namespace {

// Puts `taken` back in front of what was pushed meanwhile.
template <typename T>
void requeue(std::vector<T>& taken, std::vector<T>& pending) {
  taken.insert(taken.end(), pending.begin(), pending.end());
  pending.swap(taken);
}

}  // namespace

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
  const auto event_count = static_cast<std::int64_t>(events.size());
  const auto frame_count = static_cast<std::int64_t>(frames.size());
  lock.unlock();
  std::string error;
  try {
    store_.write_events(events);
    events.clear();
    store_.write_frames(frames);
    frames.clear();
    store_.write_samples(samples);
  } catch (const std::exception& e) {
    error = e.what();
  }
  lock.lock();
  if (!error.empty()) {
    ++stats_.failed_commits;
    stats_.last_error = error;
    requeue(samples, pending_samples_);
    requeue(events, pending_events_);
    requeue(frames, pending_frames_);
    committed_.notify_all();
    return false;
  }
  stats_.samples_committed += static_cast<std::int64_t>(samples.size());
  stats_.events_committed += event_count;
  stats_.frames_committed += frame_count;
  ++stats_.batches_committed;
  committed_since_alive_ = true;
  committed_generation_ = generation;
  committed_.notify_all();
  return true;
}

}  // namespace bosfuse::storage
