// The `bosfuse` Python module: joins the bindings of each subject.
#include <pybind11/pybind11.h>

#include "python/bindings.h"

PYBIND11_MODULE(bosfuse, m) {
  m.doc() = "bosfuse: BOS displacement fields, Newton's-law fits and run stores, NumPy in and NumPy out";
  bosfuse::python::bind_errors(m);
  bosfuse::python::bind_field(m);
  bosfuse::python::bind_evaluate(m);
  bosfuse::python::bind_fit(m);
  bosfuse::python::bind_run(m);
}
