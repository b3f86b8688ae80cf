#pragma once
// process_run: what `bosfuse process` does to a run, callable in-process by
// the command line, the demo and the benchmarks.
//
// Every non-reference frame is evaluated against the run's reference frame
// (run_selection.h) — the full displacement field, or only windows at the
// thermocouples' image positions (probe mode). Full fields are written as
// CSV under RUN/fields/p<processing>/ together with the temperature field of
// the physical model (bos_geometry.h, temperature_field.h). Probe
// temperatures come from the run's newest calibration when there is one,
// else from the model's field (full mode), else the probe's Newton fit is
// made on its shift. Every thermocouple and every probe series gets a Newton
// fit, each thermocouple–probe pair an agreement, and the last frame an
// image quality index against the reference. All times are experiment
// seconds from the run's one origin (storage/experiment_clock.h), and every
// fit has t = 0 there.
//
// The settings used (processing_settings.h) are stored with the results.
// Results are written aside, one frame per transaction, while the work goes
// on; they replace the run's current results in one transaction only when
// every frame is done. While one frame is evaluated, the next is decoded on
// a second thread (frame_prefetch.h), and, when asked, the one before gets
// its temperature field and field files on another; results are staged on
// the calling thread, in frame order, either way. A processing that is interrupted (Ctrl-C, a crash,
// kill -9) leaves the current results as they were, and `resume` continues
// it with its own settings from the first frame it had not finished. One
// frame's work, and what other threads or processes exchange to do it, is
// process_frame.h.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "pipeline/frame_distributor.h"
#include "pipeline/process_times.h"
#include "pipeline/processing_settings.h"
#include "storage/processing_store.h"

namespace bosfuse::pipeline {

struct ProcessProgress {
  std::size_t done = 0;  // frames evaluated so far (resumed ones included)
  std::size_t total = 0;
  std::string line;    // what just happened, in words
  bool frame = false;  // a frame was just evaluated; else `line` is a note (settings, geometry)
};

struct ProcessOptions {
  SettingsOverrides overrides;  // on top of the run's stored settings
  bool resume = false;          // continue the run's interrupted processing (no overrides allowed)
  std::function<void(const ProcessProgress&)> progress;  // may be empty
  const std::atomic<bool>* stop = nullptr;  // when it becomes true: stop after the current frame, resumable
  // Frames decoded ahead of the evaluation, on a second thread (frame_prefetch.h);
  // 0 decodes each on the calling thread. Each costs a frame's memory (32 MB at
  // 16 MP, 16 bits) and gives the same results.
  int prefetch_frames = 1;
  // A frame's temperature field and field files are made on a second thread
  // while the next frame is evaluated, and the frame staged after; false: in
  // turn. Either way "stop" stages the frame evaluated last before it returns.
  // Off by default: on two cores the second thread slows the evaluation
  // about as much as it saves (process_bench BM_ProcessRun16MP), and the
  // concurrent Poisson solve adds ~200 MB at 16 MP.
  bool finish_aside = false;
  // Frames evaluated side by side, each by a thread with its own context
  // (frame_threads.h): 0 chooses (one per core, at most four); 1 evaluates
  // one frame at a time, with `prefetch_frames` and `finish_aside`. The
  // results are the same either way.
  int frames_at_once = 0;
  // When set, the frames are evaluated by several processes (cluster/: MPI
  // ranks), this one included, and this one alone writes the run's store;
  // the stored results are those of a processing here. Each process then
  // evaluates one frame at a time (frames_at_once, prefetch_frames and
  // finish_aside are not used).
  FrameDistributor* distributor = nullptr;

  std::string Validate() const;  // empty when valid
};

struct ProcessReport {
  std::int64_t processing_id = 0;
  bool complete = false;  // false: stopped on request; the run's earlier results are untouched
  std::size_t frames = 0;
  std::size_t frames_resumed = 0;  // already done by the interrupted processing this one continued
  std::size_t probes = 0;
  std::size_t fits_ok = 0;
  std::size_t fits = 0;
  std::size_t agreements = 0;
  // Frames refused as not showing the reference's background (process_frame.h:
  // CheckedEvaluation): their probes hold no temperature.
  std::size_t frames_refused = 0;
  std::string temperature_source;  // calibration, physical model, none
  // This process's temperature solver, which its frames side by side share:
  // the fields it recovered, its analyses of the Poisson system and its
  // numeric factorisations (the other fields only solved). Other MPI ranks
  // count their own.
  int temperature_fields = 0;
  int temperature_analyses = 0;
  int temperature_factorisations = 0;
  double seconds = 0;
  ProcessTimes times;
  std::string text;  // what a person reads at the end
};

// A run with no frames, or only reference frames, has nothing for BOS to
// evaluate: its thermocouples get their fits as in a run with frames, stored
// as a complete processing without probes, agreements or fields (its
// summary's `thermocouples_only` says why), and a progress note says so.
// A run with frames but no reference frame is refused (split_frames).
// A processing that fails is recorded as failed (ProcessingStore::
// fail_processing): abandoned when it had finished no frame, else left
// resumable at the failing frame; either way its summary holds the error.
ProcessReport process_run(const std::filesystem::path& run_dir, const ProcessOptions& options);

// The error a failed processing recorded (its summary's `failure`); empty
// for one that did not fail, or whose summary cannot be read.
std::string processing_failure(const storage::ProcessingRecord& processing);

}  // namespace bosfuse::pipeline
