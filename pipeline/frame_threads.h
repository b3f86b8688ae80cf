#pragma once
// FrameThreads: a job's frames evaluated side by side by several threads of
// this process, each with an evaluation context of its own — made from the
// job's plan, as an MPI rank makes it — and taken in frame order on the
// calling thread (the FrameDistributor contract). Use it where a frame's
// work is partly single-threaded: a 16 MP frame decodes its PNG, solves its
// temperature field and writes its field files on one core each, so one
// frame at a time leaves cores idle that frames side by side keep busy
// (docs/BENCHMARKS.md, "A 16 MP run"). Each thread holds a
// context's memory (~600 MB at 16 MP).
//
// The first thread runs the job's own `local` work (the caller's context);
// the others prepare theirs from the plan when run() starts. Frames are
// handed out one at a time to whichever thread is free. A frame that fails
// stops the handing out; frames before it are taken, and run() rethrows its
// exception once every thread has finished the frame it held.

#include <string>

#include "pipeline/frame_distributor.h"

namespace bosfuse::pipeline {

class FrameThreads : public FrameDistributor {
 public:
  // `threads` ≥ 1 frames at once; `prepare` makes a thread's work from the plan.
  FrameThreads(int threads, std::function<FrameWork(const Bytes& plan)> prepare);

  std::size_t run(const Bytes& plan, std::size_t count, const FrameWork& local, const TakeFrame& take,
                  const std::atomic<bool>* stop) override;
  std::string brief_report() const override;

  // Frames side by side when not told: one per core, at most four (each
  // holds a context's memory).
  static int default_threads();

 private:
  int threads_;
  std::function<FrameWork(const Bytes& plan)> prepare_;
  std::vector<std::size_t> frames_by_thread_;
};

}  // namespace bosfuse::pipeline
