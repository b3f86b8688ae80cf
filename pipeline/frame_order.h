#pragma once
// FrameOrder: the bookkeeping every FrameDistributor (frame_distributor.h)
// needs whatever carries its frames, threads of this process
// (frame_threads.h) or MPI ranks (cluster/frame_farm.h): the next frame to
// hand out, the finished results not yet taken, and the first failure.
// Results come out strictly in frame order and none from the first failed
// frame on, which is what makes a distributed job store what one process
// evaluating the frames in turn would store. It is not synchronised: a
// distributor whose workers are threads holds its own lock around it.

#include <atomic>
#include <cstddef>
#include <exception>
#include <map>
#include <optional>
#include <utility>

#include "pipeline/frame_distributor.h"

namespace bosfuse::pipeline {

class FrameOrder {
 public:
  // Frames [0, count); handing out ends early when *stop becomes true.
  FrameOrder(std::size_t count, const std::atomic<bool>* stop);

  // True while a frame is left to hand out and nothing failed or asked to stop.
  bool handing_out() const;
  // The next frame to hand out, or nothing (see handing_out).
  std::optional<std::size_t> next();

  void done(std::size_t index, Bytes result);
  // Frame `index` failed; the lowest failed index is the one reported.
  void failed(std::size_t index, std::exception_ptr error);

  // The next result in frame order when it is finished and no earlier or
  // equal frame failed; the caller takes it, then asks again.
  std::optional<std::pair<std::size_t, Bytes>> pop_next();
  std::size_t taken() const { return taken_; }

  bool has_failed() const { return failure_.has_value(); }
  // Throws the first failure, if any.
  void rethrow_failure() const;

 private:
  const std::size_t count_;
  const std::atomic<bool>* stop_;
  std::size_t next_ = 0;
  std::size_t taken_ = 0;
  std::map<std::size_t, Bytes> done_;  // finished, not yet taken
  std::optional<std::pair<std::size_t, std::exception_ptr>> failure_;
};

}  // namespace bosfuse::pipeline
