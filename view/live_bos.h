#pragma once
// LiveBos evaluates a watched run's frames as they arrive, on a thread of
// its own, only at the probes (pipeline/live_probes.h: displacement, BOS
// temperature, quality index and a small view, from one decoding of each
// frame). It falls behind gracefully: it always takes the newest frame, and
// frames that arrived while it worked are skipped and counted, never queued.
// Results stay in memory for the streams, so a page opened late sees the
// whole live series; they are the viewer's own and never written to the run
// (`process` makes the stored ones). Until the run has a reference frame
// and a positioned channel, its state says what it waits for, and it tries
// again when the next frame arrives.

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "pipeline/live_probes.h"
#include "view/run_watch.h"

namespace bosfuse::view {

struct LiveBosResult {
  pipeline::LiveFrame frame;  // without its thumbnail
  std::int64_t evaluated = 0;  // frames evaluated so far, this one included
  std::int64_t skipped = 0;    // frames skipped so far, being newer ones' elders
};

struct LiveBosState {
  std::string state;  // "waiting for …", "live", or why evaluation failed
  std::string temperature_source;
  double camera_offset_s = 0;
  std::int64_t evaluated = 0;
  std::int64_t skipped = 0;
};

class LiveBos {
 public:
  // Starts the thread; `watch` must outlive this.
  explicit LiveBos(RunWatch& watch, pipeline::LiveProbeOptions options = {});
  ~LiveBos();
  LiveBos(const LiveBos&) = delete;
  LiveBos& operator=(const LiveBos&) = delete;

  std::vector<LiveBosResult> results_from(std::size_t index) const;
  LiveBosState state() const;
  // The newest evaluated frame's view as PNG bytes; empty before the first.
  std::string latest_frame_png() const;

 private:
  void run();
  void evaluate_new_frames(storage::RunTail& tail);
  void set_state(const std::string& state);

  RunWatch& watch_;
  pipeline::LiveProbeOptions options_;
  std::optional<pipeline::LiveProbes> probes_;  // the thread's own
  std::int64_t last_frame_id_ = 0;              // the thread's own

  mutable std::mutex mutex_;
  std::vector<LiveBosResult> results_;
  LiveBosState state_;
  std::string latest_png_;
  bool stopping_ = false;
  std::thread thread_;  // last: starts once everything above exists
};

}  // namespace bosfuse::view
