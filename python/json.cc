#include "python/json.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

template <typename Json>
py::object convert(const Json& j) {
  if (j.is_null()) return py::none();
  if (j.is_boolean()) return py::bool_(j.template get<bool>());
  if (j.is_number_unsigned()) return py::int_(j.template get<std::uint64_t>());
  if (j.is_number_integer()) return py::int_(j.template get<std::int64_t>());
  if (j.is_number_float()) return py::float_(j.template get<double>());
  if (j.is_string()) return py::str(j.template get<std::string>());
  if (j.is_array()) {
    py::list out;
    for (const auto& item : j) out.append(convert(item));
    return out;
  }
  py::dict out;
  for (auto it = j.begin(); it != j.end(); ++it) out[py::str(it.key())] = convert(it.value());
  return out;
}

}  // namespace

py::object to_python(const nlohmann::ordered_json& j) { return convert(j); }
py::object to_python(const nlohmann::json& j) { return convert(j); }

}  // namespace bosfuse::python
