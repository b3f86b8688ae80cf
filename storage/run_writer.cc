#include "storage/run_writer.h"

#include <exception>

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

void RunWriter::push(std::span<const Sample> samples) {
  bool full = false;
  {
    std::lock_guard lock(mutex_);
    pending_samples_.insert(pending_samples_.end(), samples.begin(), samples.end());
    ++pushed_generation_;
    full = pending_samples_.size() >= options_.max_batch_samples;
  }
  if (full) wake_writer_.notify_one();
}

void RunWriter::push(const Event& event) {
  std::lock_guard lock(mutex_);
  pending_events_.push_back(event);
  ++pushed_generation_;
}

void RunWriter::push(const FrameRecord& frame) {
  std::lock_guard lock(mutex_);
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
  std::unique_lock lock(mutex_);
  for (;;) {
    wake_writer_.wait_for(lock, options_.flush_interval, [&] {
      return stopping_ || pending_samples_.size() >= options_.max_batch_samples ||
             committed_generation_ < pushed_generation_;
    });
    const bool committed = commit_pending(lock);
    if (stopping_ && (committed || pushed_generation_ == committed_generation_)) break;
    if (stopping_ && !committed) {
      // A store that keeps failing at shutdown: give it a few more tries,
      // then give up loudly (stats().last_error says why).
      static constexpr int kShutdownRetries = 5;
      bool saved = false;
      for (int i = 0; i < kShutdownRetries && !saved; ++i) {
        lock.unlock();
        std::this_thread::sleep_for(options_.flush_interval);
        lock.lock();
        saved = commit_pending(lock);
      }
      break;
    }
  }
  stats_.uncommitted_at_stop =
      static_cast<std::int64_t>(pending_samples_.size() + pending_events_.size() + pending_frames_.size());
  writer_done_ = true;
  committed_.notify_all();
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
  committed_generation_ = generation;
  committed_.notify_all();
  return true;
}

}  // namespace bosfuse::storage
