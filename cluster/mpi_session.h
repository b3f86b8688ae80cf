#pragma once
// MpiSession: this process's part in an MPI job — the ranks mpirun or srun
// started, numbered 0 … size-1 — and the one way its messages travel: whole
// byte strings, each with a tag saying what it is. Make one per process, on
// the thread that will make every MPI call, before any other MPI use; its
// destructor ends the session (MPI_Finalize), which waits for every rank.
//
// Waiting is done by polling with short sleeps, never by a blocking MPI
// receive: Open MPI's blocking calls spin a core at 100 %, and on a node
// every core belongs to some rank's evaluation threads.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace bosfuse::cluster {

using Bytes = std::vector<std::uint8_t>;

struct Message {
  int source = 0;
  int tag = 0;
  Bytes bytes;
};

class MpiSession {
 public:
  static constexpr int kAnySource = -1;

  // Throws std::runtime_error when MPI cannot be started.
  MpiSession();
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  const std::string& host() const { return host_; }  // the node this rank runs on
  int ranks_on_this_node() const { return node_ranks_; }
  // The evaluation threads a rank should use when not told: the cores the
  // launcher bound it to, or, unbound, its share of the node's cores.
  int default_threads() const;
  std::string name() const;  // "rank 2 on node7", for messages

  void send(int to, int tag, const Bytes& bytes) const;
  // A message that has arrived from `from` (or any rank), without waiting.
  std::optional<Message> poll(int from = kAnySource) const;
  // The next message from `from` (or any rank), however long it takes.
  Message wait(int from = kAnySource) const;

 private:
  int rank_ = 0;
  int size_ = 1;
  int node_ranks_ = 1;
  std::string host_;
};

// A tag's payload that starts with a frame index: [index, 8 bytes][rest].
Bytes with_index(std::uint64_t index, const Bytes& rest = {});
Bytes with_index(std::uint64_t index, const std::string& rest);
std::uint64_t index_of(const Bytes& payload);
Bytes rest_of(const Bytes& payload);

}  // namespace bosfuse::cluster
