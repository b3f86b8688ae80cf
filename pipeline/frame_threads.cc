#include "pipeline/frame_threads.h"

#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

namespace bosfuse::pipeline {

namespace {

// What the threads share: the next frame to hand out, the results not yet
// taken and the first failure.
class Round {
 public:
  Round(std::size_t count, const std::atomic<bool>* stop) : count_(count), stop_(stop) {}

  // The next frame for a free thread; nothing when there is none to do.
  std::optional<std::size_t> next() {
    std::lock_guard lock(mutex_);
    if (next_ >= count_ || failure_ || (stop_ && stop_->load())) return std::nullopt;
    return next_++;
  }

  void done(std::size_t index, Bytes result) {
    std::lock_guard lock(mutex_);
    results_.emplace(index, std::move(result));
    changed_.notify_all();
  }

  // The first frame that failed is the one reported.
  void failed(std::size_t index, std::exception_ptr error) {
    std::lock_guard lock(mutex_);
    if (!failure_ || index < failure_->first) failure_.emplace(index, std::move(error));
    changed_.notify_all();
  }

  void thread_ended() {
    std::lock_guard lock(mutex_);
    ++ended_;
    changed_.notify_all();
  }

  // The calling thread's part: takes results in frame order as they come,
  // until every thread has ended. Returns the frames taken.
  std::size_t take_in_order(const TakeFrame& take, int threads) {
    std::size_t taken = 0;
    std::unique_lock lock(mutex_);
    for (;;) {
      changed_.wait(lock, [&] { return results_.count(taken) || ended_ == threads; });
      auto it = results_.find(taken);
      if (it == results_.end() || (failure_ && taken >= failure_->first)) break;
      const Bytes result = std::move(it->second);
      results_.erase(it);
      lock.unlock();
      try {
        take(taken, result);
      } catch (...) {
        lock.lock();
        failure_.emplace(taken, std::current_exception());  // stops the handing out; rethrown after the threads end
        break;
      }
      lock.lock();
      ++taken;
    }
    return taken;
  }

  void rethrow_failure() const {
    if (failure_) std::rethrow_exception(failure_->second);
  }

 private:
  const std::size_t count_;
  const std::atomic<bool>* stop_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::size_t next_ = 0;
  int ended_ = 0;
  std::map<std::size_t, Bytes> results_;
  std::optional<std::pair<std::size_t, std::exception_ptr>> failure_;
};

}  // namespace

FrameThreads::FrameThreads(int threads, std::function<FrameWork(const Bytes& plan)> prepare)
    : threads_(threads), prepare_(std::move(prepare)) {
  if (threads_ < 1) throw std::invalid_argument(fmt::format("{} frames at once: at least 1", threads_));
}

int FrameThreads::default_threads() {
  return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 4u));
}

std::size_t FrameThreads::run(const Bytes& plan, std::size_t count, const FrameWork& local, const TakeFrame& take,
                              const std::atomic<bool>* stop) {
  Round round(count, stop);
  frames_by_thread_.assign(static_cast<std::size_t>(threads_), 0);
  auto work_through = [&](int thread) {
    try {
      const FrameWork work = thread == 0 ? local : prepare_(plan);
      while (const auto index = round.next()) {
        try {
          round.done(*index, work(*index));
          ++frames_by_thread_[static_cast<std::size_t>(thread)];
        } catch (...) {
          round.failed(*index, std::current_exception());
        }
      }
    } catch (...) {
      round.failed(count, std::current_exception());  // its context could not be made: the job fails
    }
    round.thread_ended();
  };
  std::size_t taken = 0;
  {
    std::vector<std::jthread> threads;
    for (int t = 0; t < threads_; ++t) threads.emplace_back(work_through, t);
    taken = round.take_in_order(take, threads_);
  }
  round.rethrow_failure();
  return taken;
}

std::string FrameThreads::brief_report() const {
  std::string text = fmt::format("{} frames side by side:", threads_);
  for (std::size_t t = 0; t < frames_by_thread_.size(); ++t) {
    text += fmt::format(" {}{} frames", t ? ", " : "", frames_by_thread_[t]);
  }
  return text + "\n";
}

}  // namespace bosfuse::pipeline
