// bosfuse.Run's recorded part: the run's channels, devices, events, frames
// and samples (python/run.h).
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <filesystem>

#include "python/arrays.h"
#include "python/bindings.h"
#include "python/run.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"

namespace py = pybind11;

namespace bosfuse::python {

py::object record(const py::dict& fields) { return py::module_::import("types").attr("SimpleNamespace")(**fields); }

namespace {

template <typename T>
py::object optional(const std::optional<T>& v) {
  return v ? py::cast(*v) : py::none();
}

}  // namespace

Run::Run(const std::filesystem::path& path)
    : store_(storage::RunStore::open_as_found(path)),
      abandoned_(storage::RunStore::abandoned(path)),
      clock_(storage::experiment_clock(store_)) {}

std::string Run::status() const {
  return abandoned_ ? "interrupted" : std::string(storage::to_string(store_.run().status));
}

py::list Run::channels() const {
  py::list out;
  for (const auto& c : store_.channels()) {
    out.append(record(py::dict(py::arg("id") = c.id, py::arg("device_id") = c.device_id, py::arg("name") = c.name,
                               py::arg("kind") = c.kind, py::arg("unit") = c.unit,
                               py::arg("tc_type") = optional(c.tc_type), py::arg("image_x_px") = optional(c.image_x_px),
                               py::arg("image_y_px") = optional(c.image_y_px),
                               py::arg("resolution") = optional(c.resolution))));
  }
  return out;
}

py::list Run::devices() const {
  py::list out;
  for (const auto& d : store_.devices()) {
    out.append(record(py::dict(py::arg("id") = d.id, py::arg("name") = d.name, py::arg("kind") = d.kind,
                               py::arg("profile") = d.profile, py::arg("address") = d.address)));
  }
  return out;
}

py::list Run::events() const {
  py::list out;
  for (const auto& e : store_.events()) {
    out.append(record(py::dict(py::arg("id") = e.id, py::arg("device_id") = optional(e.device_id),
                               py::arg("t_s") = clock_.seconds(e.t_ns), py::arg("kind") = e.kind,
                               py::arg("message") = e.message)));
  }
  return out;
}

py::list Run::frames() const {
  py::list out;
  for (const auto& f : store_.frames()) {
    out.append(record(py::dict(py::arg("id") = f.id, py::arg("t_s") = clock_.seconds(f.t_ns),
                               py::arg("path") = (store_.dir() / f.path).string(), py::arg("width_px") = f.width_px,
                               py::arg("height_px") = f.height_px, py::arg("bit_depth") = f.bit_depth,
                               py::arg("is_reference") = f.is_reference)));
  }
  return out;
}

storage::FrameRecord Run::frame(long i) const {
  auto frames = store_.frames();
  const long n = static_cast<long>(frames.size());
  if (i < -n || i >= n) {
    throw py::index_error("frame " + std::to_string(i) + ": the run has " + std::to_string(n) + " frames");
  }
  return frames[i < 0 ? i + n : i];
}

const storage::ProcessingStore& Run::results() const {
  if (!results_) results_ = std::make_unique<storage::ProcessingStore>(store_.dir());
  return *results_;
}

std::int64_t Run::channel_id(const py::object& channel) const {
  if (py::hasattr(channel, "id") && !py::isinstance<py::str>(channel)) return channel.attr("id").cast<std::int64_t>();
  const auto name = channel.cast<std::string>();
  for (const auto& c : store_.channels()) {
    if (c.name == name) return c.id;
  }
  throw py::key_error("the run has no channel '" + name + "'");
}

py::tuple Run::samples(const py::object& channel) const {
  const std::int64_t id = channel_id(channel);
  storage::SampleColumns columns;
  {
    py::gil_scoped_release release;
    columns = store_.read_sample_columns(id);
  }
  const std::size_t n = columns.t_ns.size();
  py::array_t<double> t(static_cast<py::ssize_t>(n)), v(static_cast<py::ssize_t>(n));
  py::array_t<std::int8_t> s(static_cast<py::ssize_t>(n));
  double* tp = t.mutable_data();
  std::int8_t* sp = s.mutable_data();
  for (std::size_t i = 0; i < n; ++i) {
    tp[i] = clock_.seconds(columns.t_ns[i]);
    sp[i] = static_cast<std::int8_t>(columns.status[i]);
  }
  std::copy(columns.value.begin(), columns.value.end(), v.mutable_data());
  return py::make_tuple(t, v, s);
}

namespace {

// {channel name: DataFrame(t_s, value, status)} (needs pandas).
py::dict to_pandas(const Run& run) {
  py::module_ pd = py::module_::import("pandas");
  py::dict out;
  for (auto c : run.channels()) {
    const py::tuple s = run.samples(py::reinterpret_borrow<py::object>(c));
    out[c.attr("name")] = pd.attr("DataFrame")(py::dict(py::arg("t_s") = s[0], py::arg("value") = s[1],
                                                        py::arg("status") = s[2]));
  }
  return out;
}

}  // namespace

void bind_run(py::module_& m) {
  py::class_<Run> run(m, "Run", "Run(path): a recorded run, read-only, in experiment seconds");
  run
      .def(py::init<const std::filesystem::path&>(), py::arg("path"))
      .def_property_readonly("path", &Run::path)
      .def_property_readonly("status", &Run::status,
                             "complete, running, or interrupted (also a run whose logger died, left unwritten)")
      .def_property_readonly("channels", &Run::channels)
      .def_property_readonly("devices", &Run::devices)
      .def_property_readonly("events", &Run::events)
      .def_property_readonly("frames", &Run::frames)
      .def_property_readonly("time_scale", [](const Run& r) { return r.clock().time_scale; })
      .def_property_readonly("time_basis", [](const Run& r) { return r.clock().basis(); })
      .def("samples", &Run::samples, py::arg("channel"),
           "(t_s, value, status) NumPy arrays of a channel (object or name); value NaN where status != 0")
      .def("to_pandas", &to_pandas, "{channel name: pandas.DataFrame(t_s, value, status)} (needs pandas)")
      .def_property_readonly("config", [](const Run& r) { return r.store().run().config_toml; },
                             "the experiment file the run was recorded with (TOML text; tomllib.loads reads it)");
  bind_run_results(run);
}

}  // namespace bosfuse::python
