#include "app/ranks.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <opencv2/core.hpp>
#include <stdexcept>

#ifdef BOSFUSE_HAVE_MPI
#include "cluster/frame_farm.h"
#include "cluster/mpi_session.h"
#endif

namespace bosfuse::app {

bool started_as_mpi_rank() {
  // Open MPI's mpirun; PMIx (Open MPI ≥ 4, srun --mpi=pmix); PMI-1/2 (srun --mpi=pmi2, MPICH's hydra).
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"}) {
    if (std::getenv(name)) return true;
  }
  return false;
}

void run_on_ranks(std::optional<int> threads, const LeadRank& lead, const PreparePlan& prepare) {
  if (threads && *threads < 1) throw std::invalid_argument(fmt::format("--threads {}: at least 1", *threads));
  if (!started_as_mpi_rank()) {
    if (threads) cv::setNumThreads(*threads);
    return lead(nullptr);
  }
#ifdef BOSFUSE_HAVE_MPI
  cluster::MpiSession session;
  cv::setNumThreads(threads.value_or(session.default_threads()));
  if (session.size() == 1) return lead(nullptr);
  if (session.rank() != 0) {
    // Quiet unless asked (-v): rank 0 speaks for the job.
    if (spdlog::get_level() > spdlog::level::debug) spdlog::set_level(spdlog::level::warn);
    spdlog::set_pattern(fmt::format("[{}] %l: %v", session.name()));
    return cluster::serve_frames(session, prepare);
  }
  spdlog::debug("{} of {}, {} on this node, {} threads each", session.name(), session.size(),
                session.ranks_on_this_node(), cv::getNumThreads());
  cluster::FrameFarm farm(session);
  lead(&farm);
#else
  (void)prepare;
  throw std::runtime_error(
      "started by an MPI launcher, but this bosfuse was built without MPI (install libopenmpi-dev and rebuild: "
      "scripts/bootstrap); run it without mpirun");
#endif
}

}  // namespace bosfuse::app
