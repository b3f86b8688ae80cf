#include "report/sequence_export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "report/field_export.h"
#include "report/field_conventions.h"
#include "report/hdf5_writer.h"
#include "report/xdmf_sidecar.h"
#include "storage/experiment_clock.h"
#include "storage/partial_file.h"

namespace bosfuse::report {
namespace {

namespace fs = std::filesystem;

// Bumped when a reader would have to change: files say which layout they follow.
constexpr std::int64_t kLayoutVersion = 1;
// The flag of every node of a frame that has no field (its status says why).
constexpr std::uint8_t kFrameNotEvaluated = 255;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Quantity {
  std::string_view dataset;
  std::string_view units;
  std::string_view description;
  bool uint8;
};

constexpr Quantity kQuantities[] = {
    {"u_px", "px",
     "displacement along x of frame i against the reference (DESIGN.md convention); NaN where valid is 0 and for "
     "a frame whose status is not ok",
     false},
    {"v_px", "px", "displacement along y (down); as u_px", false},
    {"peak_ratio", "1", "first / second correlation peak height; NaN where valid is 0 and for a failed frame", false},
    {"sigma_u_px", "px",
     "standard uncertainty of u_px (correlation statistics on the final pass's windows; a replaced outlier its "
     "neighbours' spread); 0 where not estimated, NaN where valid is 0 and for a failed frame",
     false},
    {"sigma_v_px", "px", "standard uncertainty of v_px; as sigma_u_px", false},
    {"valid", "1", "1 where (u, v) was measured (flag 0), else 0", true},
    {"flag", "1",
     "why a node is or is not a measurement: 0 ok, 1 outlier replaced by its neighbours' median, 2 no texture, "
     "3 masked, 4 out of the region of interest, 5 no correlation peak, 6 beyond the search range (peak on the "
     "search bound), 255 the frame was not evaluated (status)",
     true},
};

std::vector<double> axis(double first, double step, int count) {
  std::vector<double> values;
  for (int i = 0; i < count; ++i) values.push_back(first + step * i);
  return values;
}

}  // namespace

struct SequenceFieldWriter::State {
  State(const fs::path& destination, SequenceExportInfo information)
      : info(std::move(information)),
        hdf5_path(destination),
        h5_file(destination),
        xmf_file(xdmf_path_for(destination)),
        out(h5_file.path(), destination),
        written(info.frame_names.size(), false),
        t_ns(info.frame_names.size()),
        time_source(info.frame_names.size(), "none"),
        status(info.frame_names.size(), "not evaluated") {}

  SequenceExportInfo info;
  fs::path hdf5_path;
  storage::PartialFile h5_file, xmf_file;  // before `out`: the file is closed before an uncommitted one is removed
  hdf5::Writer out;
  std::vector<bool> written;
  std::vector<std::optional<std::int64_t>> t_ns;
  std::vector<std::string> time_source, status;
};

SequenceFieldWriter::SequenceFieldWriter(const fs::path& hdf5_path, SequenceExportInfo info) {
  if (hdf5_path.filename().empty() || hdf5_path.extension() == ".xmf" || hdf5_path == "-") {
    throw std::invalid_argument(fmt::format(
        "--out '{}': name the HDF5 file (e.g. fields.h5); its .xmf sidecar goes beside it", hdf5_path.string()));
  }
  if (const fs::path folder = hdf5_path.parent_path(); !folder.empty() && !fs::is_directory(folder)) {
    throw std::invalid_argument(fmt::format("cannot write '{}': no folder '{}'", hdf5_path.string(), folder.string()));
  }
  if (info.frame_names.empty() || info.grid.rows < 1 || info.grid.cols < 1) {
    throw std::invalid_argument("a sequence export needs at least one frame and one grid node");
  }
  state_ = std::make_unique<State>(hdf5_path, std::move(info));
  auto& out = state_->out;
  const auto& in = state_->info;
  const std::size_t frames = in.frame_names.size(), rows = in.grid.rows, cols = in.grid.cols;
  out.set_attribute("/", "title", "bosfuse displacement fields of an image sequence against one reference");
  out.set_attribute("/", "bosfuse_version", BOSFUSE_VERSION);
  out.set_attribute("/", "layout_version", kLayoutVersion);
  out.set_attribute("/", "content",
                    "frame i of the sequence: frame_name[i], t_s[i], time_source[i], status[i] and the fields "
                    "u_px[i], v_px[i], peak_ratio[i], sigma_u_px[i], sigma_v_px[i], valid[i], flag[i] ([ny, nx], nodes at x_px, y_px); see "
                    "docs/REPORT.md, Sequence fields");
  out.set_attribute("/", "reference", in.reference);
  out.set_attribute("/", "settings", in.settings_json);
  out.set_attribute("/", "frames", static_cast<std::int64_t>(frames));
  out.set_attribute("/", "displacement_convention", kDisplacementConvention);
  out.set_attribute("/", "coordinates", coordinates_convention("fields are [frames, ny, nx]"));
  auto describe = [&](const std::string& path, std::string_view units, std::string_view what) {
    out.set_attribute(path, "units", units);
    out.set_attribute(path, "description", what);
  };
  out.write_1d("/x_px", axis(in.grid.x0_px, in.grid.step_px, in.grid.cols));
  describe("/x_px", "px", "x of each column of the fields (image coordinates)");
  out.write_1d("/y_px", axis(in.grid.y0_px, in.grid.step_px, in.grid.rows));
  describe("/y_px", "px", "y of each row of the fields (image coordinates, down)");
  for (const auto& q : kQuantities) {
    const std::string path = "/" + std::string(q.dataset);
    if (q.uint8) {
      out.create_frames(path, frames, rows, cols, q.dataset == "flag" ? kFrameNotEvaluated : std::uint8_t{0});
    } else {
      out.create_frames(path, frames, rows, cols, kNaN);
    }
    describe(path, q.units, q.description);
  }
}

SequenceFieldWriter::~SequenceFieldWriter() = default;

void SequenceFieldWriter::write(std::size_t index, const pipeline::SequenceFrameResult& frame) {
  auto& s = *state_;
  if (index >= s.written.size()) {
    throw std::out_of_range(fmt::format("frame {} of a sequence of {}", index, s.written.size()));
  }
  if (s.written[index]) throw std::logic_error(fmt::format("frame {} ({}) written twice", index, frame.name));
  if (frame.name != s.info.frame_names[index]) {
    throw std::logic_error(
        fmt::format("frame {} is {}, not {}: results out of order", index, s.info.frame_names[index], frame.name));
  }
  s.t_ns[index] = frame.time.t_ns;
  s.time_source[index] = pipeline::to_string(frame.time.source);
  s.status[index] = frame.status;
  if (frame.ok()) {
    const auto& field = frame.field;
    if (field.rows != s.info.grid.rows || field.cols != s.info.grid.cols) {
      throw std::invalid_argument(fmt::format("frame {} ({}): a {}x{} field for a {}x{} grid", index, frame.name,
                                              field.cols, field.rows, s.info.grid.cols, s.info.grid.rows));
    }
    std::vector<double> u, v, peak, sigma_u, sigma_v;
    std::vector<std::uint8_t> valid, flag;
    // What was not measured carries no number (docs/REPORT.md, "Not measured").
    constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();
    for (const auto& node : field.vectors) {
      const bool measured = node.valid();
      u.push_back(measured ? node.u_px : kNotMeasured);
      v.push_back(measured ? node.v_px : kNotMeasured);
      peak.push_back(measured ? node.peak_ratio : kNotMeasured);
      sigma_u.push_back(measured ? node.sigma_u_px : kNotMeasured);
      sigma_v.push_back(measured ? node.sigma_v_px : kNotMeasured);
      valid.push_back(measured ? 1 : 0);
      flag.push_back(static_cast<std::uint8_t>(node.flag));
    }
    s.out.write_frame("/u_px", index, u);
    s.out.write_frame("/v_px", index, v);
    s.out.write_frame("/peak_ratio", index, peak);
    s.out.write_frame("/sigma_u_px", index, sigma_u);
    s.out.write_frame("/sigma_v_px", index, sigma_v);
    s.out.write_frame("/valid", index, valid);
    s.out.write_frame("/flag", index, flag);
  }
  s.written[index] = true;
}

SequenceExportResult SequenceFieldWriter::commit() {
  auto& s = *state_;
  if (const auto missing = std::find(s.written.begin(), s.written.end(), false); missing != s.written.end()) {
    const auto index = static_cast<std::size_t>(missing - s.written.begin());
    throw std::logic_error(fmt::format("frame {} ({}) was never written", index, s.info.frame_names[index]));
  }
  SequenceExportResult result;
  result.hdf5_path = s.hdf5_path;
  result.xdmf_path = xdmf_path_for(s.hdf5_path);
  result.frames = s.written.size();
  result.frames_ok = static_cast<std::size_t>(std::count(s.status.begin(), s.status.end(), "ok"));
  for (const auto& t : s.t_ns) {
    if (t && (!result.time_origin_ns || *t < *result.time_origin_ns)) result.time_origin_ns = t;
  }
  std::vector<double> t_s;
  for (const auto& t : s.t_ns) {
    t_s.push_back(t ? static_cast<double>(*t - *result.time_origin_ns) * 1e-9 : kNaN);
  }
  auto& out = s.out;
  out.write_1d("/frame_name", s.info.frame_names);
  out.set_attribute("/frame_name", "units", "1");
  out.set_attribute("/frame_name", "description", "each frame's path as the pattern or folder gave it");
  out.write_1d("/t_s", t_s);
  out.set_attribute("/t_s", "units", "s");
  out.set_attribute("/t_s", "description",
                    "when each frame was taken, in seconds since the earliest of them (time_origin_utc); NaN when "
                    "unknown");
  out.write_1d("/time_source", s.time_source);
  out.set_attribute("/time_source", "units", "1");
  out.set_attribute("/time_source", "description",
                    "where t_s came from: exif (DateTimeOriginal + SubSecTimeOriginal, the camera's clock read as "
                    "UTC), exif_offset (with OffsetTimeOriginal applied), mtime (the file's modification time), none");
  out.write_1d("/status", s.status);
  out.set_attribute("/status", "units", "1");
  out.set_attribute("/status", "description", "ok, or why the frame has no field (its arrays are NaN, flag 255)");
  out.set_attribute("/", "frames_ok", static_cast<std::int64_t>(result.frames_ok));
  out.set_attribute("/", "time",
                    "t_s: seconds since time_origin_utc, the earliest frame time; a frame's time is its EXIF capture "
                    "time, else its file's modification time (time_source)");
  out.set_attribute("/", "time_origin_utc",
                    result.time_origin_ns ? storage::format_iso8601_utc(*result.time_origin_ns, 6) : "unknown");
  out.close();

  XdmfCollection collection{"displacement", {}};
  for (std::size_t i = 0; i < s.written.size(); ++i) {
    if (s.status[i] != "ok") continue;  // nothing to show
    XdmfFrame& frame = collection.frames.emplace_back();
    frame.name = fmt::format("frame_{:06d}", i);
    frame.t_s = t_s[i];
    frame.rows = static_cast<std::size_t>(s.info.grid.rows);
    frame.cols = static_cast<std::size_t>(s.info.grid.cols);
    frame.x_dataset = "/x_px";
    frame.y_dataset = "/y_px";
    for (const auto& q : kQuantities) {
      frame.arrays.push_back({std::string(q.dataset), "/" + std::string(q.dataset), q.uint8, i, s.written.size()});
    }
  }
  write_xdmf(s.xmf_file.path(), s.hdf5_path.filename().string(), {collection});
  s.h5_file.commit();
  s.xmf_file.commit();
  return result;
}

}  // namespace bosfuse::report
