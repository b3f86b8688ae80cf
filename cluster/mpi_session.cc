#include "cluster/mpi_session.h"

#include <mpi.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace bosfuse::cluster {

MpiSession::MpiSession() {
  int provided = 0;
  // Only the thread that made the session calls MPI; the evaluation's own
  // threads never do.
  if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    throw std::runtime_error("MPI could not be started");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  char host[MPI_MAX_PROCESSOR_NAME] = {};
  int length = 0;
  MPI_Get_processor_name(host, &length);
  host_.assign(host, static_cast<std::size_t>(length));
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node);
  MPI_Comm_size(node, &node_ranks_);
  MPI_Comm_free(&node);
}

int MpiSession::default_threads() const {
  cpu_set_t mine;
  CPU_ZERO(&mine);
  const int bound = sched_getaffinity(0, sizeof mine, &mine) == 0 ? CPU_COUNT(&mine) : 0;
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  if (bound > 0 && bound < cores) return bound;
  return std::max(1, cores / std::max(1, node_ranks_));
}

MpiSession::~MpiSession() { MPI_Finalize(); }

std::string MpiSession::name() const { return "rank " + std::to_string(rank_) + " on " + host_; }

void MpiSession::send(int to, int tag, const Bytes& bytes) const {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

std::optional<Message> MpiSession::poll(int from) const {
  int arrived = 0;
  MPI_Status status;
  MPI_Iprobe(from == kAnySource ? MPI_ANY_SOURCE : from, MPI_ANY_TAG, MPI_COMM_WORLD, &arrived, &status);
  if (!arrived) return std::nullopt;
  int count = 0;
  MPI_Get_count(&status, MPI_BYTE, &count);
  Message m{status.MPI_SOURCE, status.MPI_TAG, Bytes(static_cast<std::size_t>(count))};
  MPI_Recv(m.bytes.data(), count, MPI_BYTE, m.source, m.tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return m;
}

Message MpiSession::wait(int from) const {
  for (;;) {
    if (auto m = poll(from)) return std::move(*m);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

Bytes with_index(std::uint64_t index, const Bytes& rest) {
  Bytes out(sizeof index + rest.size());
  std::memcpy(out.data(), &index, sizeof index);
  std::copy(rest.begin(), rest.end(), out.begin() + sizeof index);
  return out;
}

Bytes with_index(std::uint64_t index, const std::string& rest) {
  return with_index(index, Bytes(rest.begin(), rest.end()));
}

std::uint64_t index_of(const Bytes& payload) {
  if (payload.size() < sizeof(std::uint64_t)) throw std::runtime_error("an MPI message without its frame index");
  std::uint64_t index = 0;
  std::memcpy(&index, payload.data(), sizeof index);
  return index;
}

Bytes rest_of(const Bytes& payload) { return Bytes(payload.begin() + sizeof(std::uint64_t), payload.end()); }

}  // namespace bosfuse::cluster
