// bosfuse.Run: a recorded run read-only (storage::RunStore::open_as_found):
// a run whose logger died is reported as interrupted and left as it is.
// Everything in experiment seconds (storage/experiment_clock.h), as every
// command shows it.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "python/arrays.h"
#include "python/bindings.h"
#include "storage/experiment_clock.h"
#include "storage/run_store.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

py::object record(const py::dict& fields) { return py::module_::import("types").attr("SimpleNamespace")(**fields); }

template <typename T>
py::object optional(const std::optional<T>& v) {
  return v ? py::cast(*v) : py::none();
}

class Run {
 public:
  explicit Run(const std::filesystem::path& path)
      : store_(storage::RunStore::open_as_found(path)),
        abandoned_(storage::RunStore::abandoned(path)),
        clock_(storage::experiment_clock(store_)) {}

  std::string status() const {
    return abandoned_ ? "interrupted" : std::string(storage::to_string(store_.run().status));
  }

  py::list channels() const {
    py::list out;
    for (const auto& c : store_.channels()) {
      out.append(record(py::dict(py::arg("id") = c.id, py::arg("device_id") = c.device_id, py::arg("name") = c.name,
                                 py::arg("kind") = c.kind, py::arg("unit") = c.unit,
                                 py::arg("tc_type") = optional(c.tc_type), py::arg("image_x_px") = optional(c.image_x_px),
                                 py::arg("image_y_px") = optional(c.image_y_px))));
    }
    return out;
  }

  py::list devices() const {
    py::list out;
    for (const auto& d : store_.devices()) {
      out.append(record(py::dict(py::arg("id") = d.id, py::arg("name") = d.name, py::arg("kind") = d.kind,
                                 py::arg("profile") = d.profile, py::arg("address") = d.address)));
    }
    return out;
  }

  py::list events() const {
    py::list out;
    for (const auto& e : store_.events()) {
      out.append(record(py::dict(py::arg("id") = e.id, py::arg("device_id") = optional(e.device_id),
                                 py::arg("t_s") = clock_.seconds(e.t_ns), py::arg("kind") = e.kind,
                                 py::arg("message") = e.message)));
    }
    return out;
  }

  py::list frames() const {
    py::list out;
    for (const auto& f : store_.frames()) {
      out.append(record(py::dict(py::arg("id") = f.id, py::arg("t_s") = clock_.seconds(f.t_ns),
                                 py::arg("path") = (store_.dir() / f.path).string(), py::arg("width_px") = f.width_px,
                                 py::arg("height_px") = f.height_px, py::arg("bit_depth") = f.bit_depth,
                                 py::arg("is_reference") = f.is_reference)));
    }
    return out;
  }

  std::int64_t channel_id(const py::object& channel) const {
    if (py::hasattr(channel, "id") && !py::isinstance<py::str>(channel)) return channel.attr("id").cast<std::int64_t>();
    const auto name = channel.cast<std::string>();
    for (const auto& c : store_.channels()) {
      if (c.name == name) return c.id;
    }
    throw py::key_error("the run has no channel '" + name + "'");
  }

  // (t_s, value, status): value NaN where status is not 0 (ok).
  py::tuple samples(const py::object& channel) const {
    const std::int64_t id = channel_id(channel);
    std::vector<storage::Sample> samples;
    {
      py::gil_scoped_release release;
      samples = store_.read_samples(id);
    }
    const int n = static_cast<int>(samples.size());
    auto t = grid_array<double>(1, n, [&](std::size_t i) { return clock_.seconds(samples[i].t_ns); });
    auto v = grid_array<double>(1, n, [&](std::size_t i) { return samples[i].value.value_or(NAN); });
    auto s = grid_array<std::int8_t>(1, n, [&](std::size_t i) { return static_cast<int>(samples[i].status); });
    return py::make_tuple(t.attr("reshape")(n), v.attr("reshape")(n), s.attr("reshape")(n));
  }

  const storage::ExperimentClock& clock() const { return clock_; }
  std::string path() const { return store_.dir().string(); }

 private:
  storage::RunStore store_;
  bool abandoned_;
  storage::ExperimentClock clock_;
};

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
  py::class_<Run>(m, "Run", "Run(path): a recorded run, read-only, in experiment seconds")
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
      .def("to_pandas", &to_pandas, "{channel name: pandas.DataFrame(t_s, value, status)} (needs pandas)");
}

}  // namespace bosfuse::python
