// bosfuse.Field and bosfuse.FLAG_NAMES.
#include <pybind11/stl.h>

#include "python/arrays.h"
#include "python/bindings.h"
#include "python/field.h"

namespace py = pybind11;

namespace bosfuse::python {

Field Field::from(const fusion::DisplacementField& f, std::string summary, double seconds) {
  const auto& v = f.vectors;
  Field out;
  out.x = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].x_px; });
  out.y = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].y_px; });
  out.u = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].u_px; });
  out.v = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].v_px; });
  out.valid = grid_array<bool>(f.rows, f.cols, [&](std::size_t i) { return v[i].valid(); });
  out.flag = grid_array<std::uint8_t>(f.rows, f.cols, [&](std::size_t i) { return static_cast<int>(v[i].flag); });
  out.peak_ratio = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].peak_ratio; });
  out.sigma_u = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].sigma_u_px; });
  out.sigma_v = grid_array<double>(f.rows, f.cols, [&](std::size_t i) { return v[i].sigma_v_px; });
  out.summary = std::move(summary);
  out.seconds = seconds;
  return out;
}

fusion::DisplacementField Field::to_displacement() const {
  const int rows = static_cast<int>(u.shape(0)), cols = static_cast<int>(u.shape(1));
  for (const py::array* a : std::initializer_list<const py::array*>{&x, &y, &v, &peak_ratio, &sigma_u, &sigma_v, &valid,
                                                                     &flag}) {
    if (a->ndim() != 2 || a->shape(0) != rows || a->shape(1) != cols) {
      throw py::value_error("field: its arrays differ in shape");
    }
  }
  fusion::DisplacementField f;
  f.rows = rows;
  f.cols = cols;
  f.vectors.resize(static_cast<std::size_t>(rows) * cols);
  const auto xs = x.unchecked<2>(), ys = y.unchecked<2>(), us = u.unchecked<2>(), vs = v.unchecked<2>();
  const auto ps = peak_ratio.unchecked<2>(), su = sigma_u.unchecked<2>(), sv = sigma_v.unchecked<2>();
  const auto fl = flag.unchecked<2>();
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (fl(r, c) > static_cast<int>(fusion::VectorFlag::kBeyondSearch)) {
        throw py::value_error("field: flag code " + std::to_string(fl(r, c)) + " is none of bosfuse.FLAG_NAMES");
      }
      f.at(r, c) = {xs(r, c), ys(r, c), us(r, c), vs(r, c), ps(r, c), static_cast<fusion::VectorFlag>(fl(r, c)),
                    false,    su(r, c), sv(r, c)};
    }
  }
  return f;
}

namespace {

// An xarray.Dataset on dims (y, x) with the field's columns as variables.
py::object to_xarray(const Field& f) {
  py::module_ xr = py::module_::import("xarray");
  py::dict coords;
  coords["x"] = f.x.attr("__getitem__")(py::make_tuple(0, py::slice(0, f.x.shape(1), 1)));
  coords["y"] = f.y.attr("__getitem__")(py::make_tuple(py::slice(0, f.y.shape(0), 1), 0));
  py::dict vars;
  const py::tuple dims = py::make_tuple("y", "x");
  for (const auto& [name, array] : std::initializer_list<std::pair<const char*, py::object>>{
           {"u", f.u}, {"v", f.v}, {"valid", f.valid}, {"flag", f.flag}, {"peak_ratio", f.peak_ratio},
           {"sigma_u", f.sigma_u}, {"sigma_v", f.sigma_v}}) {
    vars[name] = py::make_tuple(dims, array);
  }
  return xr.attr("Dataset")(vars, py::arg("coords") = coords);
}

std::vector<std::string> flag_names() {
  std::vector<std::string> names;
  for (int code = 0; code <= static_cast<int>(fusion::VectorFlag::kBeyondSearch); ++code) {
    names.push_back(fusion::to_string(static_cast<fusion::VectorFlag>(code)));
  }
  return names;
}

}  // namespace

void bind_field(py::module_& m) {
  py::class_<Field>(m, "Field",
                    "A displacement field: NumPy arrays shaped (ny, nx), in px, image coordinates (x right, y down)")
      .def_readonly("x", &Field::x, "window centres' x, px")
      .def_readonly("y", &Field::y, "window centres' y, px")
      .def_readonly("u", &Field::u, "displacement along x, px (0 where not measured)")
      .def_readonly("v", &Field::v, "displacement along y, px (0 where not measured)")
      .def_readonly("valid", &Field::valid, "True where the vector is a measurement (flag ok)")
      .def_readonly("flag", &Field::flag, "why a vector is or is not a measurement: codes, see bosfuse.FLAG_NAMES")
      .def_readonly("peak_ratio", &Field::peak_ratio, "first / second correlation peak")
      .def_readonly("sigma_u", &Field::sigma_u, "standard uncertainty of u, px (0: not estimated)")
      .def_readonly("sigma_v", &Field::sigma_v, "standard uncertainty of v, px (0: not estimated)")
      .def_readonly("summary", &Field::summary, "the evaluation's one-line report")
      .def_readonly("seconds", &Field::seconds, "the library's own time for the evaluation, s (0: a stored field)")
      .def_property_readonly("shape", [](const Field& f) { return py::make_tuple(f.u.shape(0), f.u.shape(1)); })
      .def("to_xarray", &to_xarray, "The field as an xarray.Dataset on dims (y, x) (needs xarray)")
      .def("__repr__", [](const Field& f) {
        return "<bosfuse.Field " + std::to_string(f.u.shape(0)) + "x" + std::to_string(f.u.shape(1)) + ">";
      });
  m.attr("FLAG_NAMES") = py::cast(flag_names());
}

}  // namespace bosfuse::python
