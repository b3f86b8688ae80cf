#pragma once
// run_sequence: what `bosfuse evaluate --sequence` does, callable in-process.
// Every frame of an image sequence (image_sequence.h) is evaluated against
// one reference (sequence_evaluation.h), here or, given a distributor, by
// the ranks of an MPI job, and handed in frame order to a sink (the
// command's HDF5 writer, report/sequence_export.h, bound through
// SequenceSink so this level needs no writer). A frame that cannot be
// evaluated is counted and named, and the others go on; the sink is
// committed only once every frame is in, so a run stopped on request leaves
// nothing behind.
//
// An MPI job's other ranks evaluate from the plan rank 0 sends through the
// distributor: the frames as rank 0 listed them and the settings it
// resolved, which each rank resolves again from the same command line and
// must find the same (sequence_frame_work).

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/frame_distributor.h"
#include "pipeline/processing_settings.h"
#include "pipeline/sequence_evaluation.h"

namespace bosfuse::pipeline {

// What an output is laid out with before the first frame is evaluated.
struct SequenceLayout {
  std::string reference;                 // the reference image's path as given
  std::string settings_json;             // sequence_settings_json()
  std::vector<std::string> frame_names;  // in sequence order
  fusion::GridGeometry grid;             // every field's nodes
};

// Where a sequence's results go, and who shows their progress.
class SequenceSink {
 public:
  virtual ~SequenceSink() = default;
  // Once the frames are listed and the reference checked, before any frame.
  virtual void open(const SequenceLayout& layout) = 0;
  // Frame `index` of `count`, in frame order, each once, on the calling thread.
  virtual void write(std::size_t index, std::size_t count, const SequenceFrameResult& result) = 0;
  // A frame could not be evaluated: `line` names it and says why.
  virtual void warn(const std::string& line) = 0;
  // Every frame is written; what follows is the closing report (a progress
  // display ends its line here).
  virtual void frames_done() = 0;
  // Makes the output whole. Not called when the run was stopped.
  virtual void commit() = 0;
};

struct SequenceRunOptions {
  std::string reference;  // the reference image
  std::string sequence;   // a folder or a glob pattern of frames (image_sequence.h)
  // The resolved settings (resolve_runless_settings) with the command line's
  // own choices applied; only the evaluator and the mask are used.
  ProcessingSettings settings;
  // The file the settings came from ('' for none), named when ranks disagree.
  std::string settings_file;
  // The command line's names of the choices the stored settings have no key
  // for, recorded with the settings.
  std::string subpixel = "auto";
  std::string interpolator = "bspline5";
  const std::atomic<bool>* stop = nullptr;  // when it becomes true: stop after the frames in flight
  // When set, the frames are evaluated by several processes (cluster/: MPI
  // ranks), this one included, and this one alone writes the sink.
  FrameDistributor* distributor = nullptr;

  std::string Validate() const;  // empty when valid
};

struct SequenceRunSummary {
  std::size_t frames = 0;         // in the sequence
  std::size_t frames_taken = 0;   // written to the sink (fewer than `frames` when stopped)
  std::size_t frames_failed = 0;  // of those taken, the ones with no field

  bool complete() const { return frames_taken == frames; }
};

// Throws, before the sink is opened, when the reference, the mask or the
// settings are unusable or the sequence names no frame
// (SequenceEvaluator, list_image_sequence); a distributor's errors as run()
// throws them.
SequenceRunSummary run_sequence(const SequenceRunOptions& options, SequenceSink& sink);

// What the output's `settings` record holds: the stored settings' keys
// (processing_settings.h) for an evaluation without a run, and the
// command line's own choices.
std::string sequence_settings_json(const SequenceRunOptions& options);

// An MPI rank's work on the plan rank 0 sent; throws when the settings this
// rank resolved (`options`) differ from rank 0's.
FrameWork sequence_frame_work(const SequenceRunOptions& options, const Bytes& plan);

}  // namespace bosfuse::pipeline
