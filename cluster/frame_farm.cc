#include "cluster/frame_farm.h"

#include <fmt/format.h>

#include <chrono>
#include <exception>
#include <future>
#include <map>
#include <optional>
#include <stdexcept>
#include <thread>

#include "pipeline/frame_order.h"

namespace bosfuse::cluster {
namespace {

using pipeline::Bytes;
using Clock = std::chrono::steady_clock;

enum Tag : int { kPlan = 1, kNoJob, kFrame, kStop, kReady, kResult, kError };

// The index an error carries when a rank could not set the plan up at all.
constexpr std::uint64_t kSetUp = ~std::uint64_t{0};

double seconds_between(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

Bytes text_bytes(const std::string& text) { return Bytes(text.begin(), text.end()); }

}  // namespace

// One run(): which rank holds which frame, the results not yet taken, and
// the first failure. Its destructor (also when `take` throws) waits for
// every rank to finish what it holds and tells each to stop.
class FrameFarm::Round {
 public:
  Round(FrameFarm& farm, std::size_t count, const pipeline::FrameWork& local, const pipeline::TakeFrame& take,
        const std::atomic<bool>* stop)
      : farm_(farm),
        local_(local),
        take_(take),
        order_(count, stop),
        state_(static_cast<std::size_t>(farm.session_.size()), State::kPreparing) {
    state_[0] = State::kIdle;
  }

  ~Round() {
    closing_ = true;
    try {
      while (remote_in_flight()) handle(farm_.session_.wait());
    } catch (...) {
      // A message that cannot be read while unwinding: the stops below still go out.
    }
    for (int rank = 1; rank < farm_.session_.size(); ++rank) farm_.session_.send(rank, kStop, {});
  }

  // Hands out and takes frames until none is left, or none is in flight
  // after a stop or a failure; rethrows the failure.
  std::size_t go() {
    for (;;) {
      bool acted = start_local();
      acted = collect_local() || acted;
      while (auto m = farm_.session_.poll()) {
        handle(std::move(*m));
        acted = true;
      }
      take_in_order();
      if (!local_running_.valid() && !remote_in_flight() && !handing_out()) break;
      if (!acted) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    order_.rethrow_failure();
    return order_.taken();
  }

 private:
  enum class State { kPreparing, kIdle, kBusy };

  bool handing_out() const { return !closing_ && order_.handing_out(); }

  bool remote_in_flight() const {
    for (std::size_t rank = 1; rank < state_.size(); ++rank) {
      if (state_[rank] != State::kIdle) return true;
    }
    return false;
  }

  void give(int rank) {
    if (!handing_out()) {
      state_[rank] = State::kIdle;
      return;
    }
    since_[rank] = Clock::now();
    state_[rank] = State::kBusy;
    farm_.session_.send(rank, kFrame, with_index(*order_.next()));
  }

  void handle(Message m) {
    const int rank = m.source;
    switch (m.tag) {
      case kReady:
        farm_.hosts_[rank] = std::string(m.bytes.begin(), m.bytes.end());
        break;
      case kResult: {
        auto& tally = farm_.tally_[rank];
        ++tally.frames;
        tally.busy_s += seconds_between(since_[rank], Clock::now());
        farm_.result_bytes_ += m.bytes.size();
        ++farm_.remote_frames_;
        order_.done(index_of(m.bytes), rest_of(m.bytes));
        break;
      }
      case kError: {
        const std::uint64_t index = index_of(m.bytes);
        const Bytes text = rest_of(m.bytes);
        order_.failed(index == kSetUp ? 0 : index,
                      std::make_exception_ptr(std::runtime_error(std::string(text.begin(), text.end()))));
        if (index == kSetUp) {
          state_[rank] = State::kIdle;  // never given a frame
          return;
        }
        break;
      }
      default:
        order_.failed(0, std::make_exception_ptr(std::runtime_error(
                             fmt::format("an unexpected MPI message (tag {}) from rank {}", m.tag, rank))));
    }
    give(rank);
  }

  bool start_local() {
    if (local_running_.valid() || !handing_out()) return false;
    local_index_ = *order_.next();
    local_since_ = Clock::now();
    local_running_ = std::async(std::launch::async, [this, index = local_index_] { return local_(index); });
    return true;
  }

  bool collect_local() {
    if (!local_running_.valid() || local_running_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
      return false;
    }
    try {
      order_.done(local_index_, local_running_.get());
      ++farm_.tally_[0].frames;
      farm_.tally_[0].busy_s += seconds_between(local_since_, Clock::now());
    } catch (...) {
      order_.failed(local_index_, std::current_exception());
    }
    return true;
  }

  void take_in_order() {
    while (const auto result = order_.pop_next()) {
      const auto start = Clock::now();
      take_(result->first, result->second);
      farm_.take_s_ += seconds_between(start, Clock::now());
    }
  }

  FrameFarm& farm_;
  const pipeline::FrameWork& local_;
  const pipeline::TakeFrame& take_;
  pipeline::FrameOrder order_;
  std::vector<State> state_;  // by rank; rank 0's own frames run in local_running_
  std::map<int, Clock::time_point> since_;
  std::future<Bytes> local_running_;
  std::size_t local_index_ = 0;
  Clock::time_point local_since_;
  bool closing_ = false;
};

FrameFarm::FrameFarm(const MpiSession& session)
    : session_(session),
      tally_(static_cast<std::size_t>(session.size())),
      hosts_(static_cast<std::size_t>(session.size())) {
  hosts_[0] = session.host();
}

FrameFarm::~FrameFarm() {
  if (planned_) return;
  for (int rank = 1; rank < session_.size(); ++rank) session_.send(rank, kNoJob, {});
}

std::size_t FrameFarm::run(const pipeline::Bytes& plan, std::size_t count, const pipeline::FrameWork& local,
                           const pipeline::TakeFrame& take, const std::atomic<bool>* stop) {
  if (planned_) throw std::logic_error("FrameFarm::run is called once");
  const auto start = Clock::now();
  for (int rank = 1; rank < session_.size(); ++rank) session_.send(rank, kPlan, plan);
  planned_ = true;
  std::size_t taken = 0;
  {
    Round round(*this, count, local, take, stop);
    taken = round.go();
  }
  taken_ = taken;
  seconds_ = seconds_between(start, Clock::now());
  return taken;
}

std::string FrameFarm::brief_report() const {
  std::string text = fmt::format("distributed over {} MPI ranks in {:.1f} s:\n", session_.size(), seconds_);
  for (std::size_t rank = 0; rank < tally_.size(); ++rank) {
    text += fmt::format("  rank {} on {}: {} frames, busy {:.1f} s\n", rank, hosts_[rank].empty() ? "?" : hosts_[rank],
                        tally_[rank].frames, tally_[rank].busy_s);
  }
  if (remote_frames_ > 0) {
    text += fmt::format("  results sent to rank 0: {:.1f} kB a frame\n",
                        static_cast<double>(result_bytes_) / remote_frames_ / 1e3);
  }
  if (taken_ > 0) {
    const double ms = 1e3 * take_s_ / static_cast<double>(taken_);
    text += fmt::format("  rank 0 wrote the results: {:.2f} ms a frame (the writer's limit: {:.0f} frames/s)\n", ms,
                        1e3 / ms);
  }
  return text;
}

void serve_frames(const MpiSession& session,
                  const std::function<pipeline::FrameWork(const pipeline::Bytes& plan)>& prepare) {
  const Message plan = session.wait(0);
  if (plan.tag != kPlan) return;  // rank 0 failed before it had a job
  pipeline::FrameWork work;
  try {
    work = prepare(plan.bytes);
    session.send(0, kReady, text_bytes(session.host()));
  } catch (const std::exception& e) {
    session.send(0, kError, with_index(kSetUp, session.name() + ": " + e.what()));
  }
  for (;;) {
    const Message m = session.wait(0);
    if (m.tag != kFrame) return;  // stop
    const std::uint64_t index = index_of(m.bytes);
    try {
      session.send(0, kResult, with_index(index, work(index)));
    } catch (const std::exception& e) {
      session.send(0, kError, with_index(index, session.name() + ": " + e.what()));
    }
  }
}

}  // namespace bosfuse::cluster
