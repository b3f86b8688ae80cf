#pragma once
// How a command that evaluates frames runs: in this process, or — started
// by mpirun or srun — as one rank of an MPI job (cluster/frame_farm.h).
// Rank 0 runs the command as it would alone, with a distributor handing its
// frames to every rank; the other ranks only evaluate what they are handed,
// silently (warnings and errors still go to their standard error; mpirun
// prefixes nothing, so each says which rank it is).

#include <functional>
#include <optional>

#include "pipeline/frame_distributor.h"

namespace bosfuse::app {

// The command itself: `distributor` is null when it runs alone.
using LeadRank = std::function<void(pipeline::FrameDistributor* distributor)>;
// The other ranks' side: the work of a plan the lead sent (the pipeline's own).
using PreparePlan = std::function<pipeline::FrameWork(const pipeline::Bytes& plan)>;

// Evaluation threads: `threads` when given, else, in an MPI job, the
// rank's share of its node (cluster/mpi_session.h), else OpenCV's default
// (every core). Throws when mpirun started a bosfuse built without MPI.
void run_on_ranks(std::optional<int> threads, const LeadRank& lead, const PreparePlan& prepare);

// Whether an MPI launcher (mpirun, srun) started this process.
bool started_as_mpi_rank();

}  // namespace bosfuse::app
