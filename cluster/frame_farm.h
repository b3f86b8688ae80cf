#pragma once
// FrameFarm: a job's frames handed out by rank 0 to every rank of an MPI
// job, one frame at a time to whichever rank asks next (frame costs differ:
// adaptive refinement, decoding, a slow node), so no rank idles while
// another has a queue. Rank 0 evaluates too, on a thread of its own, while
// its main thread hands out frames, collects the results and gives them to
// the job's `take` in frame order — rank 0 is the only process that writes
// the job's store or file. It is the pipeline's FrameDistributor
// (pipeline/frame_distributor.h, which states the order and error rules);
// the other ranks run serve_frames() with the pipeline's worker side.
//
// The protocol, by tag: rank 0 sends every other rank the plan (or "no
// job" when rank 0 failed before it had one); a rank that has set the plan
// up says it is ready, and then sends each frame's result (or its error),
// which also asks for the next frame; rank 0 answers with a frame index or
// "stop". Every rank gets exactly one "stop" or "no job", after which it
// leaves serve_frames() and ends its MPI session. A rank that dies is MPI's
// business: mpirun (or srun) ends the whole job with a non-zero status, and
// what rank 0 had committed stays committed.

#include <functional>
#include <string>
#include <vector>

#include "cluster/mpi_session.h"
#include "pipeline/frame_distributor.h"

namespace bosfuse::cluster {

class FrameFarm : public pipeline::FrameDistributor {
 public:
  // On rank 0 of `session`, which must outlive the farm.
  explicit FrameFarm(const MpiSession& session);
  // Tells every rank not yet given a plan that there is none (rank 0 failed
  // before run()), so none waits for ever.
  ~FrameFarm() override;
  FrameFarm(const FrameFarm&) = delete;
  FrameFarm& operator=(const FrameFarm&) = delete;

  std::size_t run(const pipeline::Bytes& plan, std::size_t count, const pipeline::FrameWork& local,
                  const pipeline::TakeFrame& take, const std::atomic<bool>* stop) override;
  std::string brief_report() const override;

 private:
  struct RankTally {
    std::size_t frames = 0;
    double busy_s = 0;  // from handing a frame out to its result's arrival
  };
  class Round;

  const MpiSession& session_;
  bool planned_ = false;
  std::vector<RankTally> tally_;  // by rank
  std::vector<std::string> hosts_;
  std::size_t result_bytes_ = 0;  // received from the other ranks
  std::size_t remote_frames_ = 0;
  std::size_t taken_ = 0;
  double take_s_ = 0;  // in the job's `take`: rank 0 writing the results
  double seconds_ = 0;
};

// On every rank but 0: waits for rank 0's plan, sets it up with `prepare`
// (its error is sent to rank 0, which fails the job with it), and evaluates
// the frames it is handed until rank 0 says stop.
void serve_frames(const MpiSession& session,
                  const std::function<pipeline::FrameWork(const pipeline::Bytes& plan)>& prepare);

}  // namespace bosfuse::cluster
