#pragma once
// The XDMF sidecar of an HDF5 field file: a small XML file ParaView (and
// VisIt) open to see the fields as temporal collections of 2-D rectilinear
// grids, the data itself staying in the HDF5 file, referenced by its name
// relative to the sidecar. The field export of a run (field_export.h) and
// the batch evaluation of an image sequence (sequence_export.h) both write
// one; only where a frame's arrays sit differs: a dataset of their own, or
// one [frame, :, :] slab of a [frames, ny, nx] dataset.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace bosfuse::report {

// One array of a frame, shown as point data named `name`.
struct XdmfArray {
  std::string name;
  std::string dataset;               // HDF5 path: [ny, nx], or [frames, ny, nx] with `frame` set
  bool uint8 = false;                // else float64
  std::optional<std::size_t> frame;  // the slab of a [frames, ny, nx] dataset
  std::size_t frames = 0;            // that dataset's frame count
};

struct XdmfFrame {
  std::string name;  // e.g. frame_000012
  double t_s = 0;
  std::size_t rows = 0, cols = 0;
  std::string x_dataset, y_dataset;  // 1-D node coordinates [nx], [ny]
  std::vector<XdmfArray> arrays;
};

struct XdmfCollection {
  std::string name;  // e.g. displacement
  std::vector<XdmfFrame> frames;
};

// Writes `path`; `h5_name` is the HDF5 file's name as the sidecar refers to
// it (beside it). Throws std::runtime_error naming `path` when it cannot be written.
void write_xdmf(const std::filesystem::path& path, std::string_view h5_name,
                const std::vector<XdmfCollection>& collections);

}  // namespace bosfuse::report
