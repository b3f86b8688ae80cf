// bosfuse.Error and its subclasses: each library exception type becomes
// one Python exception with the same message the CLI prints.
//   acquisition::ConfigError     -> bosfuse.ConfigError
//   storage::StorageError        -> bosfuse.StorageError (OutputRefused too)
//   acquisition::DeviceError     -> bosfuse.DeviceError
//   fusion::InsufficientMemory   -> bosfuse.MemoryError (also a MemoryError)
//   report::NoStoredFields       -> bosfuse.NoStoredFields
// Any other std::runtime_error of the library (a file it cannot read, a
// fit that cannot be made) is a bosfuse.Error itself. The library's
// std::invalid_argument (options that do not fit, sizes that
// differ) stays ValueError, as pybind11 maps it; the module's own checks of
// arrays raise ValueError too.
#include <pybind11/pybind11.h>

#include "acquisition/config/toml_reader.h"
#include "acquisition/device_reading.h"
#include "fusion/memory_budget.h"
#include "python/bindings.h"
#include "report/field_export.h"
#include "storage/storage_error.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

// Registered once; the translator below raises through them.
struct Errors {
  py::object base, config, storage, device, memory, no_fields;
};

Errors& errors() {
  static Errors* e = new Errors();  // never destroyed: outlives the interpreter's teardown
  return *e;
}

void translate(std::exception_ptr p) {
  const Errors& e = errors();
  try {
    if (p) std::rethrow_exception(p);
  } catch (const acquisition::ConfigError& x) {
    PyErr_SetString(e.config.ptr(), x.what());
  } catch (const storage::StorageError& x) {
    PyErr_SetString(e.storage.ptr(), x.what());
  } catch (const acquisition::DeviceError& x) {
    PyErr_SetString(e.device.ptr(), x.what());
  } catch (const fusion::InsufficientMemory& x) {
    PyErr_SetString(e.memory.ptr(), x.what());
  } catch (const report::NoStoredFields& x) {
    PyErr_SetString(e.no_fields.ptr(), x.what());
  } catch (const py::builtin_exception&) {
    throw;  // pybind11's own (ValueError, TypeError ...): its translator's
  } catch (const std::runtime_error& x) {
    PyErr_SetString(e.base.ptr(), x.what());  // any other failure the library reports (a file it cannot read)
  }
}

py::object new_error(py::module_& m, const char* name, py::handle base, const char* doc) {
  py::object type = py::reinterpret_steal<py::object>(
      PyErr_NewExceptionWithDoc((std::string("bosfuse.") + name).c_str(), doc, base.ptr(), nullptr));
  if (!type) throw py::error_already_set();
  m.attr(name) = type;
  return type;
}

}  // namespace

void bind_errors(py::module_& m) {
  Errors& e = errors();
  e.base = new_error(m, "Error", PyExc_Exception, "Base of every error the bosfuse libraries raise.");
  e.config = new_error(m, "ConfigError", e.base, "A bad setting or configuration file: the message names the key.");
  e.storage = new_error(m, "StorageError", e.base, "The run store failed (SQLite's message and the statement).");
  e.device = new_error(m, "DeviceError", e.base, "A device did not answer or answered wrongly.");
  py::tuple memory_bases = py::make_tuple(e.base, py::handle(PyExc_MemoryError));
  e.memory = py::reinterpret_steal<py::object>(PyErr_NewExceptionWithDoc(
      "bosfuse.MemoryError", "An evaluation needs more memory than the process can get.", memory_bases.ptr(),
      nullptr));
  if (!e.memory) throw py::error_already_set();
  m.attr("MemoryError") = e.memory;
  e.no_fields = new_error(m, "NoStoredFields", e.base, "The run has no stored displacement fields.");
  py::register_exception_translator(&translate);
}

}  // namespace bosfuse::python
