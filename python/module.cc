// The `bosfuse` Python module: joins the bindings of each subject.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "python/bindings.h"

PYBIND11_MODULE(bosfuse, m) {
  m.doc() = "bosfuse: BOS displacement fields, Newton's-law fits and run stores, NumPy in and NumPy out";
  // What is initialised on first use is initialised here, at import, by one
  // thread: pybind11 looks NumPy's C API up into a function-local static
  // (npy_api::get), which two threads' first arrays could otherwise meet at.
  pybind11::dtype::of<std::uint8_t>();
  bosfuse::python::bind_errors(m);
  bosfuse::python::bind_field(m);
  bosfuse::python::bind_evaluate(m);
  bosfuse::python::bind_fit(m);
  bosfuse::python::bind_run(m);
  bosfuse::python::bind_quality(m);
  bosfuse::python::bind_background(m);
  bosfuse::python::bind_temperature(m);
  bosfuse::python::bind_image(m);
}
