#pragma once
// JSON documents of the libraries (fits, agreements, settings) as plain
// Python objects: dicts, lists, numbers, None for JSON's null.

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

namespace bosfuse::python {

pybind11::object to_python(const nlohmann::ordered_json& j);
pybind11::object to_python(const nlohmann::json& j);

}  // namespace bosfuse::python
