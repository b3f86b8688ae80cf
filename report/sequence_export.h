#pragma once
// The HDF5 file of a batch-evaluated image sequence (`bosfuse evaluate
// --reference REF --sequence GLOB --out FILE.h5`, pipeline/
// sequence_evaluation.h) and its XDMF sidecar. Every frame's displacement
// field is one slab of [frames, ny, nx] arrays, with the frames' names,
// times and statuses in 1-D arrays beside them, so an h5py user takes
// u_px[i] and finds its frame at frame_name[i]. The layout and reading
// examples are in docs/REPORT.md ("Sequence fields"); its conventions
// (units and description on every dataset, image coordinates, [ny, nx]
// order, gzip + shuffle) are the run field export's (field_export.h).
//
// SequenceFieldWriter is made once the frames are listed and the grid is
// known, takes each frame's result as it comes — in any order, each once, so
// a parallel driver can gather results to one writer — holding only one
// field at a time, and commit() adds the per-frame tables and renames both
// files into place. A writer destroyed without commit() (an error, Ctrl-C)
// leaves the destination as it was.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fusion/field_warp.h"
#include "pipeline/sequence_evaluation.h"

namespace bosfuse::report {

struct SequenceExportInfo {
  std::string reference;                 // the reference image's path as given
  std::string settings_json;             // the evaluation's settings, stored as the `settings` attribute
  std::vector<std::string> frame_names;  // in sequence order; frame i's result must carry name i
  fusion::GridGeometry grid;             // every field's nodes
};

struct SequenceExportResult {
  std::filesystem::path hdf5_path;
  std::filesystem::path xdmf_path;
  std::size_t frames = 0;
  std::size_t frames_ok = 0;
  std::optional<std::int64_t> time_origin_ns;  // t_s = 0: the earliest frame time; none when no frame has one
};

class SequenceFieldWriter {
 public:
  // Creates the file under a temporary name beside `hdf5_path` and lays out
  // its arrays. Throws std::invalid_argument for a name that is not an HDF5
  // file's or a folder that does not exist, hdf5::Hdf5Error when HDF5 fails.
  SequenceFieldWriter(const std::filesystem::path& hdf5_path, SequenceExportInfo info);
  ~SequenceFieldWriter();
  SequenceFieldWriter(const SequenceFieldWriter&) = delete;
  SequenceFieldWriter& operator=(const SequenceFieldWriter&) = delete;

  // Frame `index`'s result; its field (when ok) must be on the grid.
  void write(std::size_t index, const pipeline::SequenceFrameResult& frame);
  // Throws std::logic_error when a frame was never written.
  SequenceExportResult commit();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace bosfuse::report
