// bosfuse.read_image(): an image file as bosfuse reads it (the decoders of
// pipeline/image_io.h), as a NumPy array at the depth it was stored.
#include "pipeline/image_io.h"
#include "python/arrays.h"
#include "python/bindings.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

py::array read_image(const py::object& path) {
  const auto text = path_argument(path);
  if (!text) throw py::type_error("path: expected a str or os.PathLike");
  cv::Mat image;
  {
    py::gil_scoped_release release;
    image = pipeline::read_image(*text, "image");
  }
  return mat_array(image);
}

}  // namespace

void bind_image(py::module_& m) {
  m.def("read_image", &read_image, py::arg("path"),
        "read_image(path) -> numpy.ndarray\n\nAn image file (PNG, TIFF, JPEG, BMP, PNM) as bosfuse reads it, at its "
        "stored depth: uint8 or uint16, (rows, cols) or (rows, cols, channels)");
}

}  // namespace bosfuse::python
