// bosfuse.evaluate() and bosfuse.Evaluator: an image pair evaluated as
// `bosfuse evaluate REF MEAS` does it (pipeline/pair_evaluation.h), and one
// reference against frame after frame keeping its preparation, as
// `process` does (fusion::DisplacementEvaluator). The GIL is released while
// the library computes; the arrays it reads stay referenced meanwhile.
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <optional>

#include "pipeline/pair_evaluation.h"
#include "python/arrays.h"
#include "python/bindings.h"
#include "python/evaluation_request.h"
#include "python/field.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

const char* kEvaluateDoc = R"(evaluate(reference, measurement, *, probes=None, settings=None, **options) -> Field

The displacement field of an image pair, as `bosfuse evaluate REF MEAS` gives it.
reference, measurement: 2-D NumPy arrays (uint8, uint16 or float32; C-contiguous ones
are not copied) or image paths. probes: [(x, y), ...] evaluates only the windows
centred there (a one-row field in their order). settings: a dict of options or a
TOML file with a [processing] table. options, named as the CLI's: window, step,
passes, max_shift, method ('xcorr' or 'flow'), flow, adaptive_refinement,
adaptive_threshold, preprocess, roi=(x, y, w, h), mask (array or path),
first_window, dis_preset, subpixel, interpolator.)";

// The pair's sizes must agree: a ValueError saying both.
void check_sizes(const cv::Mat& reference, const cv::Mat& measurement) {
  if (reference.size() == measurement.size()) return;
  throw py::value_error("reference and measurement differ in size: " + std::to_string(reference.rows) + "x" +
                        std::to_string(reference.cols) + " against " + std::to_string(measurement.rows) + "x" +
                        std::to_string(measurement.cols) + " (rows x columns)");
}

// Python objects are read while the GIL is held; files are read, and the
// pair evaluated, with it released (pure C++ from there).
Field evaluate(const py::object& reference, const py::object& measurement, const py::object& probes,
               const py::kwargs& kwargs) {
  const EvaluationRequest request = evaluation_request(kwargs);
  const ImageInput ref(reference, "reference"), meas(measurement, "measurement");
  const auto points = probes.is_none() ? std::nullopt : std::optional(probes.cast<std::vector<std::pair<double, double>>>());
  fusion::EvaluationResult result;
  {
    py::gil_scoped_release release;
    pipeline::ImagePair pair;
    pair.reference_path = ref.name();
    pair.measurement_path = meas.name();
    pair.reference = ref.read();
    pair.measurement = meas.read();
    pair.mask = request.read_mask();
    check_sizes(pair.reference, pair.measurement);  // a C++ exception: raised once the GIL is back
    std::vector<cv::Point2d> at;
    if (points) at = probe_points(*points, pair.reference.size());
    result = pipeline::evaluate_image_pair(pair, request.options, at);
  }
  return Field::from(result.field, result.summary.BriefReport(), result.summary.seconds);
}

// One reference, many measurements: the evaluator and the arrays it shares.
class Evaluator {
 public:
  Evaluator(const py::object& reference, const py::kwargs& kwargs)
      : request_(evaluation_request(kwargs)), reference_array_(reference) {
    const ImageInput ref(reference, "reference");
    py::gil_scoped_release release;
    reference_ = ref.read();
    evaluator_ = std::make_unique<fusion::DisplacementEvaluator>(reference_, request_.options, request_.read_mask());
  }

  Field process(const py::object& measurement, const py::object& probes) {
    const ImageInput meas(measurement, "measurement");
    const auto points =
        probes.is_none() ? std::nullopt : std::optional(probes.cast<std::vector<std::pair<double, double>>>());
    fusion::EvaluationResult result;
    {
      py::gil_scoped_release release;
      const cv::Mat image = meas.read();
      if (image.size() != reference_.size()) throw py::value_error("measurement: its size differs from the reference's");
      std::vector<cv::Point2d> at;
      if (points) at = probe_points(*points, image.size());
      std::lock_guard lock(mutex_);  // one frame at a time: the evaluator's buffers are reused
      result = at.empty() ? evaluator_->evaluate(image) : evaluator_->probe(image, at);
    }
    return Field::from(result.field, result.summary.BriefReport(), result.summary.seconds);
  }

 private:
  EvaluationRequest request_;
  py::object reference_array_;  // the pixels reference_ may share, kept alive
  cv::Mat reference_;
  std::unique_ptr<fusion::DisplacementEvaluator> evaluator_;
  std::mutex mutex_;
};

}  // namespace

void bind_evaluate(py::module_& m) {
  m.def("evaluate", &evaluate, kEvaluateDoc, py::arg("reference"), py::arg("measurement"), py::kw_only(),
        py::arg("probes") = py::none());
  py::class_<Evaluator>(m, "Evaluator",
                        "Evaluator(reference, **options): one reference against frame after frame, its preparation "
                        "and buffers kept between frames (options as evaluate's)")
      .def(py::init<const py::object&, const py::kwargs&>(), py::arg("reference"))
      .def("process", &Evaluator::process, py::arg("measurement"), py::kw_only(), py::arg("probes") = py::none(),
           "The field of one measurement (or of the windows at probes=[(x, y), ...]); the GIL is released meanwhile");
}

}  // namespace bosfuse::python
