#include "acquisition/device_worker.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <stdexcept>

#include "acquisition/clock.h"

namespace bosfuse::acquisition {
namespace {

constexpr std::chrono::milliseconds kFirstRestartPause{250};
constexpr std::chrono::milliseconds kLongestRestartPause{10'000};

bool is_trouble(const std::string& kind) {
  return kind == "disconnect" || kind == "error" || kind == "bad-reply" || kind == "abandoned" || kind == "skipped";
}

}  // namespace

DeviceWorker::DeviceWorker(std::string name, std::int64_t device_id, storage::RunWriter& writer)
    : name_(std::move(name)), device_id_(device_id), writer_(writer) {}

DeviceWorker::~DeviceWorker() {
  if (!thread_.joinable()) return;
  try {
    // The thread holds a reference to its worker, so the last reference may
    // be dropped on the thread itself, which cannot join itself.
    if (thread_.get_id() == std::this_thread::get_id()) {
      thread_.detach();
    } else {
      thread_.join();  // its function has returned: it released its reference
    }
  } catch (...) {
    // join() only fails on a broken thread library; a destructor must not throw.
  }
}

void DeviceWorker::start() {
  std::shared_ptr<DeviceWorker> self = weak_from_this().lock();
  if (!self) throw std::logic_error("device worker " + name_ + " must be owned by a std::shared_ptr to start");
  // spdlog makes its default logger on first use; made here, before the
  // thread starts, every thread sees it made (ThreadSanitizer cannot see the
  // guard inside the uninstrumented library).
  spdlog::default_logger_raw();
  thread_ = std::thread([self] { self->run(); });
}

void DeviceWorker::request_stop() noexcept {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
}

bool DeviceWorker::finish_stop(SteadyTime deadline) noexcept {
  if (!thread_.joinable() || thread_.get_id() == std::this_thread::get_id()) return true;
  std::unique_lock lock(mutex_);
  const bool ended = finished_.wait_until(lock, deadline, [&] { return ended_; });
  lock.unlock();
  if (ended) {
    thread_.join();
    return true;
  }
  try {
    record_event("abandoned", "stopped without waiting for a device call that had not returned");
  } catch (...) {
    // Nothing more can be said; the stop must go on.
  }
  {
    std::lock_guard sink(sink_mutex_);
    abandoned_ = true;
  }
  thread_.detach();
  return false;
}

bool DeviceWorker::stop(std::chrono::milliseconds grace) noexcept {
  request_stop();
  return finish_stop(std::chrono::steady_clock::now() + grace);
}

bool DeviceWorker::wait_until(SteadyTime deadline) {
  std::unique_lock lock(mutex_);
  return !wake_.wait_until(lock, deadline, [&] { return stopping_; });
}

bool DeviceWorker::stopping() const {
  std::lock_guard lock(mutex_);
  return stopping_;
}

void DeviceWorker::push(std::span<const storage::Sample> samples) {
  std::lock_guard sink(sink_mutex_);
  if (!abandoned_) writer_.push(samples);
}

void DeviceWorker::push(const storage::FrameRecord& frame) {
  std::lock_guard sink(sink_mutex_);
  if (!abandoned_) writer_.push(frame);
}

bool DeviceWorker::store_event(const std::string& kind, const std::string& message) {
  std::lock_guard sink(sink_mutex_);
  if (abandoned_) return false;
  writer_.push(storage::Event{0, device_id_, utc_now_ns(), kind, message});
  return true;
}

void DeviceWorker::record_event(const std::string& kind, const std::string& message) {
  if (!store_event(kind, message)) return;
  if (is_trouble(kind)) {
    spdlog::warn("{}: {}", name_, message);
  } else {
    spdlog::info("{}: {}", name_, message);
  }
}

void DeviceWorker::run() noexcept {
  auto pause = kFirstRestartPause;
  for (;;) {
    std::string failure;
    try {
      loop();
      break;
    } catch (const std::exception& e) {
      failure = e.what();
    } catch (...) {
      failure = "an unknown exception";
    }
    try {
      record_event("error", "unexpected failure (" + failure + "); the device is restarted");
      if (!wait_until(std::chrono::steady_clock::now() + pause)) break;
    } catch (...) {
      break;  // cannot even record or wait: end this device, not the process
    }
    pause = std::min(pause * 2, kLongestRestartPause);
  }
  disconnect_device();
  {
    std::lock_guard lock(mutex_);
    ended_ = true;
  }
  finished_.notify_all();
}

}  // namespace bosfuse::acquisition
