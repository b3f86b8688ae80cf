#include "report/field_export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <string_view>

#include "acquisition/clock.h"
#include "pipeline/field_csv.h"
#include "report/field_conventions.h"
#include "report/hdf5_writer.h"
#include "report/xdmf_sidecar.h"
#include "storage/experiment_clock.h"
#include "storage/partial_file.h"
#include "storage/processing_store.h"
#include "storage/run_paths.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

// Bumped when a reader would have to change: files say which layout they follow.
// 2: values are NaN where the node's flag (valid, measured) is 0, where 1 held the filled-in numbers.
constexpr std::int64_t kLayoutVersion = 2;

// A stored CSV column and the dataset it becomes.
struct Quantity {
  std::string_view column;
  std::string_view dataset;
  std::string_view units;
  std::string_view description;
  bool flag;  // 0/1, stored as uint8
};

constexpr Quantity kDisplacementQuantities[] = {
    {"u", "u_px", "px", "displacement along x (DESIGN.md convention); NaN where valid is 0", false},
    {"v", "v_px", "px", "displacement along y (down); NaN where valid is 0", false},
    {"valid", "valid", "1",
     "1 where (u, v) was measured; 0 where masked, without texture or correlation peak, or an outlier replaced by "
     "its neighbours' median",
     true},
    {"peak_ratio", "peak_ratio", "1", "first / second correlation peak height; NaN where valid is 0", false},
    {"sigma_u", "sigma_u_px", "px",
     "standard uncertainty of u (correlation statistics on the final pass's windows); NaN where valid is 0 or in a "
     "field stored before it was, 0 where not estimated",
     false},
    {"sigma_v", "sigma_v_px", "px", "standard uncertainty of v; as sigma_u_px", false},
};

constexpr Quantity kTemperatureQuantities[] = {
    {"temperature_c", "temperature_c", "degC",
     "temperature recovered from the displacement field; NaN where measured is 0 (filled in by the solve, not a "
     "measurement) or where there is none (n <= 1)",
     false},
    {"measured", "measured", "1",
     "1 where the node's displacement was measured; 0 where the temperature was filled in from the surroundings", true},
};

struct Kind {
  std::string_view name;
  std::span<const std::string_view> columns;
  std::span<const Quantity> quantities;
  std::string_view measured_column;  // the flag column: 0 where a node holds no measurement
  std::string_view description;
};

const Kind kKinds[] = {
    {"displacement", pipeline::kDisplacementColumns, kDisplacementQuantities, "valid",
     "displacement fields of the measurement frames against the reference frame, one group per frame"},
    {"temperature", pipeline::kTemperatureColumns, kTemperatureQuantities, "measured",
     "temperature fields recovered from the displacement fields, one group per frame"},
};

struct Grid {
  std::vector<double> x_px, y_px;
  std::string group;  // /grids/grid_000
};

// What the sidecar needs of one exported frame.
struct ExportedFrame {
  std::string group;  // /displacement/frame_000012
  std::int64_t frame_id = 0;
  double t_s = 0;
  std::size_t grid = 0;
  int rows = 0, cols = 0;
};

// The values where `measured` is a non-zero number, NaN elsewhere: a value the
// processing filled in (the solve's harmonic fill, a replaced outlier's
// neighbour median) is not exported as if it were measured.
std::vector<double> measured_values(const cv::Mat& values, const cv::Mat& measured) {
  std::vector<double> out;
  out.reserve(values.total());
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      const double m = measured.at<double>(r, c);
      out.push_back(std::isfinite(m) && m != 0 ? values.at<double>(r, c) : std::numeric_limits<double>::quiet_NaN());
    }
  }
  return out;
}

// A flag column: 1 where the file says non-zero, 0 where it says 0 or lacks the node.
std::vector<std::uint8_t> as_flags(const cv::Mat& values) {
  std::vector<std::uint8_t> out;
  out.reserve(values.total());
  for (int r = 0; r < values.rows; ++r) {
    for (int c = 0; c < values.cols; ++c) {
      const double v = values.at<double>(r, c);
      out.push_back(std::isfinite(v) && v != 0 ? 1 : 0);
    }
  }
  return out;
}

std::size_t grid_of(const pipeline::StoredFieldGrid& field, std::vector<Grid>& grids, hdf5::Writer& out,
                    std::optional<double> px_per_mm) {
  for (std::size_t i = 0; i < grids.size(); ++i) {
    if (grids[i].x_px == field.x_px && grids[i].y_px == field.y_px) return i;
  }
  Grid grid{field.x_px, field.y_px, fmt::format("/grids/grid_{:03d}", grids.size())};
  out.create_group(grid.group);
  out.set_attribute(grid.group, "description",
                    "node positions of a field grid; the frames on it link x_px, y_px (x_mm, y_mm) to these");
  auto axis = [&](const std::string& name, const std::vector<double>& values, std::string_view units,
                  std::string_view what) {
    const std::string path = grid.group + "/" + name;
    out.write_1d(path, values);
    out.set_attribute(path, "units", units);
    out.set_attribute(path, "description", what);
  };
  axis("x_px", grid.x_px, "px", "x of each column (image coordinates)");
  axis("y_px", grid.y_px, "px", "y of each row (image coordinates, down)");
  if (px_per_mm) {
    auto scaled = [&](const std::vector<double>& px) {
      std::vector<double> mm;
      for (const double p : px) mm.push_back(p / *px_per_mm);
      return mm;
    };
    axis("x_mm", scaled(grid.x_px), "mm", "x of each column in the flow plane: x_px / px_per_mm");
    axis("y_mm", scaled(grid.y_px), "mm", "y of each row in the flow plane (down): y_px / px_per_mm");
  }
  grids.push_back(std::move(grid));
  return grids.size() - 1;
}

// The sidecar's view of the exported frames: each frame's arrays are datasets of its own group.
std::vector<XdmfCollection> xdmf_collections(const std::vector<Grid>& grids,
                                             const std::map<std::string_view, std::vector<ExportedFrame>>& frames,
                                             bool in_mm) {
  std::vector<XdmfCollection> collections;
  const std::string x = in_mm ? "x_mm" : "x_px", y = in_mm ? "y_mm" : "y_px";
  for (const auto& kind : kKinds) {
    const auto it = frames.find(kind.name);
    if (it == frames.end()) continue;
    XdmfCollection& collection = collections.emplace_back();
    collection.name = kind.name;
    for (const auto& f : it->second) {
      XdmfFrame& frame = collection.frames.emplace_back();
      frame.name = fmt::format("frame_{:06d}", f.frame_id);
      frame.t_s = f.t_s;
      frame.rows = static_cast<std::size_t>(f.rows);
      frame.cols = static_cast<std::size_t>(f.cols);
      frame.x_dataset = grids[f.grid].group + "/" + x;
      frame.y_dataset = grids[f.grid].group + "/" + y;
      for (const auto& q : kind.quantities) {
        frame.arrays.push_back(
            {std::string(q.dataset), f.group + "/" + std::string(q.dataset), q.flag, std::nullopt, 0});
      }
    }
  }
  return collections;
}

using FramesById = std::map<std::int64_t, storage::FrameRecord>;

void check_destination(const fs::path& hdf5_path, const FieldExportOptions& options) {
  if (hdf5_path.filename().empty() || hdf5_path.extension() == ".xmf") {
    throw std::invalid_argument(
        fmt::format("'{}': name the HDF5 file (e.g. fields.h5); its .xmf sidecar goes beside it", hdf5_path.string()));
  }
  if (options.px_per_mm && !(*options.px_per_mm > 0 && std::isfinite(*options.px_per_mm))) {
    throw std::invalid_argument("px per mm must be positive");
  }
  if (const fs::path folder = hdf5_path.parent_path(); !folder.empty() && !fs::is_directory(folder)) {
    throw std::runtime_error(fmt::format("cannot write '{}': no folder '{}'", hdf5_path.string(), folder.string()));
  }
}

std::vector<storage::FieldRecord> stored_fields(const storage::RunStore& store) {
  const storage::ProcessingStore results(store.dir());
  auto rows = results.fields();
  if (rows.empty()) {
    throw NoStoredFields(fmt::format(
        "the run '{}' has no stored fields: run `bosfuse process RUN --mode full` first",
        store.dir().string()));
  }
  return rows;
}

// In time order, so the per-kind t_s arrays and the XDMF collection need no sorting.
void sort_by_frame_time(std::vector<storage::FieldRecord>& rows, const FramesById& frame_by_id) {
  // The schema allows only the two kinds and only frames of the run; a row
  // naming a frame the run lacks means the store was edited by hand.
  for (const auto& row : rows) {
    if (!frame_by_id.count(row.frame_id)) {
      throw std::runtime_error(fmt::format("stored {} field '{}' names frame {}, which the run does not have",
                                           storage::printable(row.kind), storage::printable(row.path), row.frame_id));
    }
  }
  std::sort(rows.begin(), rows.end(), [&](const auto& a, const auto& b) {
    return std::pair(frame_by_id.at(a.frame_id).t_ns, a.frame_id) <
           std::pair(frame_by_id.at(b.frame_id).t_ns, b.frame_id);
  });
}

void write_file_attributes(hdf5::Writer& out, const storage::RunInfo& run, const storage::ExperimentClock& clock,
                           const FieldExportOptions& options) {
  out.set_attribute("/", "title", fmt::format("bosfuse field export of run '{}'", run.name));
  out.set_attribute("/", "run_name", run.name);
  out.set_attribute("/", "run_started_utc", acquisition::format_iso8601_utc(run.started_ns, 3));
  out.set_attribute("/", "bosfuse_version", BOSFUSE_VERSION);
  out.set_attribute("/", "layout_version", kLayoutVersion);
  out.set_attribute("/", "content",
                    "displacement and temperature fields of the run's frames as stored by `bosfuse process`: "
                    "/displacement/frame_NNNNNN and /temperature/frame_NNNNNN (NNNNNN = frame id in the run "
                    "store), grid coordinates under /grids; see docs/REPORT.md, Field export");
  out.set_attribute("/", "displacement_convention", kDisplacementConvention);
  out.set_attribute("/", "coordinates", coordinates_convention("2-D arrays are [ny, nx]"));
  out.set_attribute("/", "time", "t_s: " + clock.basis());
  if (options.px_per_mm) out.set_attribute("/", "px_per_mm", *options.px_per_mm);
  out.create_group("/grids");
}

// What an export reads while it writes the HDF5 file, and what it has written so far.
struct ExportState {
  const storage::RunStore& store;
  const storage::ExperimentClock& clock;
  const FramesById& frame_by_id;
  std::optional<double> px_per_mm;
  std::vector<Grid> grids;
  std::map<std::string_view, std::vector<ExportedFrame>> exported;
};

// The frame's quantities as 2-D datasets of `group`: flags as 0/1, values NaN where nothing was measured.
void write_quantities(hdf5::Writer& out, const Kind& kind, const pipeline::StoredFieldGrid& field,
                      const std::string& group) {
  for (const auto& q : kind.quantities) {
    const std::string path = group + "/" + std::string(q.dataset);
    const cv::Mat& values = field.column(q.column);
    if (q.flag) {
      out.write_2d(path, as_flags(values), field.y_px.size(), field.x_px.size());
    } else {
      out.write_2d(path, measured_values(values, field.column(kind.measured_column)), field.y_px.size(),
                   field.x_px.size());
    }
    out.set_attribute(path, "units", q.units);
    out.set_attribute(path, "description", q.description);
  }
}

// One stored field as its frame's group, linked to its grid's coordinates.
ExportedFrame write_frame(hdf5::Writer& out, ExportState& state, const Kind& kind, const storage::FieldRecord& row) {
  const auto& frame = state.frame_by_id.at(row.frame_id);
  pipeline::StoredFieldGrid field;
  try {
    field = pipeline::read_stored_field(storage::resolve_in_run(state.store.dir(), row.path), kind.columns);
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("stored {} field of frame {}: {}", kind.name, frame.id, e.what()));
  }
  ExportedFrame f;
  f.group = fmt::format("/{}/frame_{:06d}", kind.name, frame.id);
  f.frame_id = frame.id;
  f.t_s = state.clock.seconds(frame.t_ns);
  f.grid = grid_of(field, state.grids, out, state.px_per_mm);
  f.rows = field.rows();
  f.cols = field.cols();
  out.create_group(f.group);
  out.set_attribute(f.group, "t_s", f.t_s);
  out.set_attribute(f.group, "frame_id", f.frame_id);
  out.set_attribute(f.group, "frame_path", frame.path);
  out.set_attribute(f.group, "field_path", row.path);
  out.set_attribute(f.group, "grid", state.grids[f.grid].group);
  out.set_attribute(f.group, "summary", row.json);
  for (const char* axis : {"x_px", "y_px", "x_mm", "y_mm"}) {
    if (state.px_per_mm || std::string_view(axis).ends_with("_px")) {
      out.link(state.grids[f.grid].group + "/" + axis, f.group + "/" + axis);
    }
  }
  write_quantities(out, kind, field, f.group);
  return f;
}

// The kind's group with a group per frame (rows in time order) and its t_s and frame_id arrays; none without frames.
void write_kind(hdf5::Writer& out, ExportState& state, const Kind& kind,
                const std::vector<storage::FieldRecord>& rows) {
  const std::string group = fmt::format("/{}", kind.name);
  std::vector<double> times_s;
  std::vector<std::int64_t> frame_ids;
  for (const auto& row : rows) {
    if (row.kind != kind.name) continue;
    if (times_s.empty()) {
      out.create_group(group);
      out.set_attribute(group, "description", kind.description);
    }
    ExportedFrame f = write_frame(out, state, kind, row);
    times_s.push_back(f.t_s);
    frame_ids.push_back(f.frame_id);
    state.exported[kind.name].push_back(std::move(f));
  }
  if (times_s.empty()) return;
  out.write_1d(group + "/t_s", times_s);
  out.set_attribute(group + "/t_s", "units", "s");
  out.set_attribute(group + "/t_s", "description", "t_s of the frames below, in time order");
  out.write_1d(group + "/frame_id", frame_ids);
  out.set_attribute(group + "/frame_id", "units", "1");
  out.set_attribute(group + "/frame_id", "description", "frame ids in the run store, in the order of t_s");
}

}  // namespace

fs::path xdmf_path_for(const fs::path& hdf5_path) { return fs::path(hdf5_path).replace_extension(".xmf"); }

FieldExportResult export_fields(const storage::RunStore& store, const fs::path& hdf5_path,
                                const FieldExportOptions& options) {
  check_destination(hdf5_path, options);
  const auto run = store.run();
  const storage::ExperimentClock clock = storage::experiment_clock(store);
  auto rows = stored_fields(store);
  FramesById frame_by_id;
  for (const auto& f : store.frames()) frame_by_id[f.id] = f;
  FieldExportResult result;
  result.hdf5_path = hdf5_path;
  result.xdmf_path = xdmf_path_for(hdf5_path);
  sort_by_frame_time(rows, frame_by_id);

  storage::PartialFile h5_file(hdf5_path), xmf_file(result.xdmf_path);
  ExportState state{store, clock, frame_by_id, options.px_per_mm, {}, {}};
  {
    hdf5::Writer out(h5_file.path(), hdf5_path);
    write_file_attributes(out, run, clock, options);
    for (const auto& kind : kKinds) write_kind(out, state, kind, rows);
    out.close();
  }
  write_xdmf(xmf_file.path(), hdf5_path.filename().string(),
             xdmf_collections(state.grids, state.exported, options.px_per_mm.has_value()));
  h5_file.commit();
  xmf_file.commit();
  result.displacement_frames = state.exported["displacement"].size();
  result.temperature_frames = state.exported["temperature"].size();
  result.grids = state.grids.size();
  return result;
}

}  // namespace bosfuse::report
