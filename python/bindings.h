#pragma once
// The bindings of the `bosfuse` Python module, one function per subject
// (each in its own *_binding.cc); module.cc calls them in this order, errors
// first, so every later binding can raise the module's exceptions.

#include <pybind11/pybind11.h>

namespace bosfuse::python {

void bind_errors(pybind11::module_& m);
void bind_field(pybind11::module_& m);
void bind_evaluate(pybind11::module_& m);
void bind_fit(pybind11::module_& m);
void bind_run(pybind11::module_& m);
void bind_quality(pybind11::module_& m);
void bind_background(pybind11::module_& m);
void bind_temperature(pybind11::module_& m);
void bind_image(pybind11::module_& m);

}  // namespace bosfuse::python
