// bosfuse.fit_newton(): Newton's law of cooling fitted to two arrays as
// `bosfuse fit` fits two columns (report/csv_fit.h), returning the dict of
// its --json: parameters, intervals, diagnostics, covariance, warnings.
#include <glog/logging.h>
#include <pybind11/stl.h>

#include <optional>

#include "fitting/newton_fit.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "python/json.h"
#include "report/csv_fit.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

const char* kFitDoc = R"(fit_newton(t_s, temperature_c, *, ambient='free', loss='none', sigma=None, confidence=0.95) -> dict

Newton's law of cooling, T = T_amb + (T0 - T_amb) exp(-k t), fitted as `bosfuse fit`
fits a time and a temperature column; returns the dict of `bosfuse fit --json`
(without its "input", which names a file). ambient: 'free', 'fixed:VALUE' or a
number, 'prior:VALUE,SIGMA'; loss: 'none', 'huber:SCALE', 'cauchy:SCALE' (°C);
sigma: the known measurement σ, °C. Times within a year of 0 count from t = 0 (as
an export's experiment seconds), epoch-scale ones from the earliest sample.)";

std::string ambient_text(const py::object& ambient) {
  if (py::isinstance<py::float_>(ambient) || py::isinstance<py::int_>(ambient)) {
    return "fixed:" + py::str(ambient).cast<std::string>();
  }
  return ambient.cast<std::string>();
}

py::object fit_newton(const py::object& t_s, const py::object& temperature_c, const py::object& ambient,
                      const std::string& loss, std::optional<double> sigma, double confidence) {
  report::CsvSeries series;
  series.time_name = "t_s";
  series.temperature_name = "temperature_c";
  series.time_s = double_vector(t_s, "t_s");
  series.temperature_c = double_vector(temperature_c, "temperature_c");
  if (series.time_s.size() != series.temperature_c.size()) {
    throw py::value_error("t_s and temperature_c differ in length: " + std::to_string(series.time_s.size()) +
                          " against " + std::to_string(series.temperature_c.size()));
  }
  fitting::NewtonFitOptions options;
  options.ambient = report::parse_ambient(ambient_text(ambient), "ambient");
  options.loss = report::parse_loss(loss, "loss");
  options.measurement_sigma_c = sigma;
  options.confidence = confidence;
  if (const auto reason = options.Validate(); !reason.empty()) throw py::value_error(reason);
  options = report::with_csv_origin(options, series);
  fitting::NewtonFit fit;
  {
    py::gil_scoped_release release;
    FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres logs rank deficiency itself; the summary says it better
    fit = fitting::fit_newton(series.time_s, series.temperature_c, options);
  }
  nlohmann::ordered_json j = report::csv_fit_json(fit, series, "");
  j.erase("input");
  return to_python(j);
}

}  // namespace

void bind_fit(py::module_& m) {
  m.def("fit_newton", &fit_newton, kFitDoc, py::arg("t_s"), py::arg("temperature_c"), py::kw_only(),
        py::arg("ambient") = "free", py::arg("loss") = "none", py::arg("sigma") = py::none(),
        py::arg("confidence") = 0.95);
}

}  // namespace bosfuse::python
