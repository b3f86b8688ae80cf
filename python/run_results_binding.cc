// bosfuse.Run's processed part: what `bosfuse process` stored beside the
// recording (docs/SCHEMA.md, "Results") — the frames' images at their
// stored depth, the stored displacement fields as Fields, the BOS probe
// series, the Newton fits and the thermocouple–probe agreements, all in
// experiment seconds. It reads only what was stored: a run not processed
// has no fields (bosfuse.NoStoredFields) and empty series, fits and
// agreements.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "pipeline/field_csv.h"
#include "pipeline/image_io.h"
#include "python/arrays.h"
#include "python/field.h"
#include "python/json.h"
#include "python/run.h"
#include "report/field_export.h"
#include "storage/run_paths.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

double or_nan(const std::optional<double>& v) { return v.value_or(NAN); }

py::array frame_image(const Run& run, long i) {
  const storage::FrameRecord frame = run.frame(i);
  const std::string path = storage::resolve_in_run(run.store().dir(), frame.path).string();
  cv::Mat image;
  {
    py::gil_scoped_release release;
    image = pipeline::read_image(path, "frame");
  }
  return mat_array(image);
}

// One node of a stored displacement file. Files written before the flag
// column (issue 30) read it as NaN: a measurement there is ok, the rest
// unmeasured (no-peak); before σ (issue 29), σ is 0, not estimated; a node
// missing from the file lies outside what was evaluated.
fusion::DisplacementVector stored_vector(const pipeline::StoredFieldGrid& g, int r, int c) {
  fusion::DisplacementVector v;
  v.x_px = g.x_px[c];
  v.y_px = g.y_px[r];
  if (!g.present.at<std::uint8_t>(r, c)) {
    v.flag = fusion::VectorFlag::kOutOfRoi;
    return v;
  }
  const auto at = [&](const char* column) { return g.column(column).at<double>(r, c); };
  const auto finite_or_0 = [](double x) { return std::isfinite(x) ? x : 0.0; };
  v.u_px = finite_or_0(at("u"));
  v.v_px = finite_or_0(at("v"));
  v.peak_ratio = finite_or_0(at("peak_ratio"));
  v.sigma_u_px = finite_or_0(at("sigma_u"));
  v.sigma_v_px = finite_or_0(at("sigma_v"));
  const double flag = at("flag");
  v.flag = std::isfinite(flag) ? static_cast<fusion::VectorFlag>(static_cast<int>(flag))
           : at("valid") == 1  ? fusion::VectorFlag::kOk
                               : fusion::VectorFlag::kNoPeak;
  return v;
}

Field stored_field(const Run& run, long i) {
  const storage::FrameRecord frame = run.frame(i);
  const auto rows = run.results().fields();
  bool any = false;
  for (const auto& row : rows) {
    if (row.kind != "displacement") continue;
    any = true;
    if (row.frame_id != frame.id) continue;
    const auto path = storage::resolve_in_run(run.store().dir(), row.path);
    pipeline::StoredFieldGrid grid;
    fusion::DisplacementField field;
    {
      py::gil_scoped_release release;
      grid = pipeline::read_stored_field(path, pipeline::kDisplacementColumns);
      field.rows = grid.rows();
      field.cols = grid.cols();
      for (int r = 0; r < field.rows; ++r) {
        for (int c = 0; c < field.cols; ++c) field.vectors.push_back(stored_vector(grid, r, c));
      }
    }
    return Field::from(field);
  }
  if (!any) {
    throw report::NoStoredFields(run.path() + ": the run has no stored displacement fields (not processed, or "
                                              "processed in probe mode); `bosfuse process RUN` stores them");
  }
  throw report::NoStoredFields(fmt::format("{}: frame {} (id {}) has no stored displacement field", run.path(), i,
                                           frame.id));
}

py::list probe_series(const Run& run) {
  py::list out;
  for (const auto& p : run.results().probes()) {
    const auto samples = run.results().probe_samples(p.id);
    const int n = static_cast<int>(samples.size());
    const auto column = [&](auto value) {
      return vector_array<double>([&] {
        std::vector<double> v(n);
        for (int k = 0; k < n; ++k) v[k] = value(samples[k]);
        return v;
      }());
    };
    py::array_t<std::int64_t> frame_id(n);
    py::array_t<bool> valid(n);
    for (int k = 0; k < n; ++k) {
      frame_id.mutable_data()[k] = samples[k].frame_id;
      valid.mutable_data()[k] = samples[k].valid;
    }
    using S = storage::ProbeSampleRecord;
    out.append(record(py::dict(
        py::arg("id") = p.id, py::arg("name") = p.name,
        py::arg("channel_id") = p.channel_id ? py::cast(*p.channel_id) : py::none(), py::arg("x_px") = p.x_px,
        py::arg("y_px") = p.y_px, py::arg("frame_id") = frame_id,
        py::arg("t_s") = column([&](const S& s) { return run.clock().seconds(s.t_ns); }),
        py::arg("u_px") = column([](const S& s) { return s.u_px; }),
        py::arg("v_px") = column([](const S& s) { return s.v_px; }),
        py::arg("shift_px") = column([](const S& s) { return s.shift_px; }),
        py::arg("temperature_c") = column([](const S& s) { return or_nan(s.temperature_c); }),
        py::arg("valid") = valid, py::arg("sigma_u_px") = column([](const S& s) { return or_nan(s.sigma_u_px); }),
        py::arg("sigma_v_px") = column([](const S& s) { return or_nan(s.sigma_v_px); }),
        py::arg("sigma_shift_px") = column([](const S& s) { return or_nan(s.sigma_shift_px); }),
        py::arg("sigma_random_c") = column([](const S& s) { return or_nan(s.sigma_random_c); }),
        py::arg("sigma_systematic_c") = column([](const S& s) { return or_nan(s.sigma_systematic_c); }))));
  }
  return out;
}

std::map<std::int64_t, std::string> channel_names(const Run& run) {
  std::map<std::int64_t, std::string> names;
  for (const auto& c : run.store().channels()) names[c.id] = c.name;
  return names;
}

std::map<std::int64_t, std::string> probe_names(const Run& run) {
  std::map<std::int64_t, std::string> names;
  for (const auto& p : run.results().probes()) names[p.id] = p.name;
  return names;
}

// The stored JSON as a dict (its keys those docs/SCHEMA.md names), beside
// what the row says of it.
py::dict stored_json(const std::string& text) { return to_python(nlohmann::ordered_json::parse(text)); }

// The name stored for `id`, or None where the row names nothing stored.
py::object name_or_none(const std::map<std::int64_t, std::string>& names, std::int64_t id) {
  const auto it = names.find(id);
  return it == names.end() ? py::none() : py::cast(it->second);
}

py::list fits(const Run& run) {
  const auto channels = channel_names(run);
  const auto probes = probe_names(run);
  py::list out;
  for (const auto& f : run.results().fits()) {
    py::dict d = stored_json(f.json);
    const bool channel = f.subject == storage::FitSubject::kChannel;
    const auto& names = channel ? channels : probes;
    d["subject"] = channel ? "channel" : "probe";
    d["subject_id"] = f.subject_id;
    d["name"] = name_or_none(names, f.subject_id);
    d["origin_t_s"] = run.clock().seconds(f.origin_t_ns);
    d["ok"] = f.ok;
    out.append(d);
  }
  return out;
}

py::list agreements(const Run& run) {
  const auto channels = channel_names(run);
  const auto probes = probe_names(run);
  py::list out;
  for (const auto& a : run.results().agreements()) {
    py::dict d = stored_json(a.json);
    d["channel_id"] = a.channel_id;
    d["probe_id"] = a.probe_id;
    d["channel"] = name_or_none(channels, a.channel_id);
    d["probe"] = name_or_none(probes, a.probe_id);
    out.append(d);
  }
  return out;
}

}  // namespace

void bind_run_results(py::class_<Run>& run) {
  run.def("frame_image", &frame_image, py::arg("i"),
          "The image of frames[i] as a NumPy array at its stored depth (uint8 or uint16; (rows, cols), or (rows, "
          "cols, channels) for colour)")
      .def("field", &stored_field, py::arg("i"),
           "The displacement field `bosfuse process` stored for frames[i], as a Field (NoStoredFields when none)")
      .def("probe_series", &probe_series,
           "The BOS probe series process stored: one object per probe (id, name, channel_id, x_px, y_px) with "
           "arrays frame_id, t_s, u_px, v_px, shift_px, temperature_c, valid and the σ columns (NaN: none)")
      .def("fits", &fits,
           "The stored Newton fits: dicts of the `bosfuse fit --json` layout (times in experiment seconds) with "
           "subject ('channel' or 'probe'), subject_id, name, origin_t_s and ok")
      .def("agreements", &agreements,
           "The stored thermocouple-probe agreements: dicts of their stored JSON with channel_id, probe_id, "
           "channel and probe (names)");
}

}  // namespace bosfuse::python
