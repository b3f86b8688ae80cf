#include "pipeline/frame_threads.h"

#include <fmt/format.h>

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "pipeline/frame_order.h"

namespace bosfuse::pipeline {

namespace {

// What the threads share: the frames' order (handed out, finished, the
// first failure) under one lock, and how many threads have ended.
class Round {
 public:
  Round(std::size_t count, const std::atomic<bool>* stop) : order_(count, stop) {}

  // The next frame for a free thread; nothing when there is none to do.
  std::optional<std::size_t> next() {
    std::lock_guard lock(mutex_);
    return order_.next();
  }

  void done(std::size_t index, Bytes result) {
    std::lock_guard lock(mutex_);
    order_.done(index, std::move(result));
    changed_.notify_all();
  }

  void failed(std::size_t index, std::exception_ptr error) {
    std::lock_guard lock(mutex_);
    order_.failed(index, std::move(error));
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
      std::optional<std::pair<std::size_t, Bytes>> result;
      changed_.wait(lock, [&] { return (result = order_.pop_next()) || ended_ == threads; });
      if (!result) return taken;
      lock.unlock();
      try {
        take(result->first, result->second);
      } catch (...) {
        lock.lock();
        // Stops the handing out; rethrown once the threads have ended.
        order_.failed(result->first, std::current_exception());
        return taken;
      }
      lock.lock();
      ++taken;
    }
  }

  void rethrow_failure() const { order_.rethrow_failure(); }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  FrameOrder order_;
  int ended_ = 0;
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
    text += fmt::format("{}{} frames", t ? ", " : " ", frames_by_thread_[t]);
  }
  return text + "\n";
}

}  // namespace bosfuse::pipeline
