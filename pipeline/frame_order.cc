#include "pipeline/frame_order.h"

namespace bosfuse::pipeline {

FrameOrder::FrameOrder(std::size_t count, const std::atomic<bool>* stop) : count_(count), stop_(stop) {}

bool FrameOrder::handing_out() const { return next_ < count_ && !failure_ && !(stop_ && stop_->load()); }

std::optional<std::size_t> FrameOrder::next() {
  if (!handing_out()) return std::nullopt;
  return next_++;
}

void FrameOrder::done(std::size_t index, Bytes result) { done_.insert_or_assign(index, std::move(result)); }

void FrameOrder::failed(std::size_t index, std::exception_ptr error) {
  if (!failure_ || index < failure_->first) failure_.emplace(index, std::move(error));
}

std::optional<std::pair<std::size_t, Bytes>> FrameOrder::pop_next() {
  if (failure_ && taken_ >= failure_->first) return std::nullopt;
  const auto it = done_.find(taken_);
  if (it == done_.end()) return std::nullopt;
  std::pair<std::size_t, Bytes> result{it->first, std::move(it->second)};
  done_.erase(it);
  ++taken_;
  return result;
}

void FrameOrder::rethrow_failure() const {
  if (failure_) std::rethrow_exception(failure_->second);
}

}  // namespace bosfuse::pipeline
