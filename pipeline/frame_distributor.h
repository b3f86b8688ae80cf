#pragma once
// FrameDistributor: frames of one job evaluated by several processes (MPI
// ranks, cluster/frame_farm.h) instead of this one alone. The pipeline says
// what a frame's work is and what to do with its result; the distributor
// says who does it. A job is described by a plan, the bytes every other
// process needs to evaluate any frame of it (settings, paths, frame list),
// and results travel as bytes too, so the pipeline's types never meet the
// transport.
//
// What every implementation guarantees: `take` is called on the calling
// thread for frames 0, 1, 2, ... in order, each once, whichever process
// evaluated it and whenever its result came; so whatever `take` stores is
// the same as one process evaluating the frames in turn would store. When a
// frame fails, frames before it are still taken, none from it on, and run()
// throws its error once nothing is in flight; on `stop` likewise without
// the error (run() returns and the caller sees frames not taken).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bosfuse::pipeline {

using Bytes = std::vector<std::uint8_t>;

// Frame i's work, given its index in the plan's frame list; throws on a
// frame that cannot be evaluated.
using FrameWork = std::function<Bytes(std::size_t index)>;
// A frame's result on the calling process, in index order.
using TakeFrame = std::function<void(std::size_t index, const Bytes& result)>;

class FrameDistributor {
 public:
  virtual ~FrameDistributor() = default;

  // Evaluates frames [0, count) with `local` on this process and with the
  // plan's own work on the others; see above for the order and errors.
  // Returns the frames taken (count unless stopped).
  virtual std::size_t run(const Bytes& plan, std::size_t count, const FrameWork& local, const TakeFrame& take,
                          const std::atomic<bool>* stop) = 0;

  // Who evaluated how many frames, and how long they worked and waited, in
  // a line per process.
  virtual std::string brief_report() const = 0;
};

}  // namespace bosfuse::pipeline
