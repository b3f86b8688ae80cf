#pragma once
// Field export: the displacement and temperature fields `bosfuse process`
// stored for a run (the `fields` rows and the CSV files they name,
// docs/SCHEMA.md), written as one HDF5 file for the tools users already have
// — h5py, MATLAB's h5read, and ParaView through an XDMF sidecar (OUT.xmf
// beside OUT.h5). It reads only what `process` stored; it evaluates nothing.
// The layout, attributes and reading examples are in docs/REPORT.md
// ("Field export").
//
// Each frame's fields are 2-D arrays shaped [ny, nx] (row = y, image
// coordinates, DESIGN.md) with `units` on every dataset, experiment time
// `t_s` (experiment seconds, storage/experiment_clock.h) on every frame; the grid's coordinates are
// stored once per distinct grid. Both files are written under temporary
// names and renamed at the end, so a failed export leaves no half file.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "storage/run_store.h"

namespace bosfuse::report {

struct FieldExportOptions {
  std::optional<double> px_per_mm;  // adds x_mm, y_mm; the XDMF geometry is in mm then, else in px
};

struct FieldExportResult {
  std::filesystem::path hdf5_path;
  std::filesystem::path xdmf_path;
  std::size_t displacement_frames = 0;
  std::size_t temperature_frames = 0;
  std::size_t grids = 0;
};

// The run has no stored field (not processed, or processed in probe mode).
class NoStoredFields : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `hdf5_path` and its sidecar (same name, extension .xmf). Throws
// NoStoredFields, or std::runtime_error naming the stored file or the HDF5
// object that failed; the destination is then left as it was.
FieldExportResult export_fields(const storage::RunStore& store, const std::filesystem::path& hdf5_path,
                                const FieldExportOptions& options = {});

// The sidecar's path for `hdf5_path`: the same name with extension .xmf.
std::filesystem::path xdmf_path_for(const std::filesystem::path& hdf5_path);

}  // namespace bosfuse::report
