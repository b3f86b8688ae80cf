#include "python/arrays.h"

#include <fmt/format.h>

#include <cstring>

#include "pipeline/image_io.h"

namespace py = pybind11;

namespace bosfuse::python {
namespace {

int mat_type(const py::dtype& dtype, const std::string& role) {
  if (dtype.is(py::dtype::of<std::uint8_t>())) return CV_8UC1;
  if (dtype.is(py::dtype::of<std::uint16_t>())) return CV_16UC1;
  if (dtype.is(py::dtype::of<float>())) return CV_32FC1;
  throw py::value_error(fmt::format("{}: dtype {} is not an image's: use uint8, uint16 or float32", role,
                                    py::str(py::handle(dtype)).cast<std::string>()));
}

}  // namespace

std::optional<std::string> path_argument(const py::handle& value) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::hasattr(value, "__fspath__")) return py::str(value.attr("__fspath__")()).cast<std::string>();
  return std::nullopt;
}

cv::Mat image_argument(const py::handle& image, const std::string& role) {
  if (auto path = path_argument(image)) return pipeline::read_image(*path, role);
  if (!py::isinstance<py::array>(image)) {
    throw py::value_error(fmt::format("{}: expected a 2-D NumPy array or a path, got {}", role,
                                      py::str(image.get_type().attr("__name__")).cast<std::string>()));
  }
  const auto array = py::reinterpret_borrow<py::array>(image);
  if (array.ndim() != 2) {
    throw py::value_error(fmt::format("{}: expected a 2-D array (rows, columns), got {} dimensions", role, array.ndim()));
  }
  const int type = mat_type(array.dtype(), role);
  if (!(array.flags() & py::array::c_style)) {
    throw py::value_error(role + ": the array is not C-contiguous; pass numpy.ascontiguousarray(...) of it");
  }
  if (array.shape(0) == 0 || array.shape(1) == 0) throw py::value_error(role + ": the array is empty");
  if (array.shape(0) > INT32_MAX || array.shape(1) > INT32_MAX) throw py::value_error(role + ": the array is too large");
  return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)), type,
                 const_cast<void*>(array.data()), static_cast<std::size_t>(array.strides(0)));
}

namespace {

py::dtype dtype_of_depth(int depth) {
  switch (depth) {
    case CV_8U: return py::dtype::of<std::uint8_t>();
    case CV_16U: return py::dtype::of<std::uint16_t>();
    case CV_32F: return py::dtype::of<float>();
    case CV_64F: return py::dtype::of<double>();
    default: throw py::value_error(fmt::format("an image of OpenCV depth {} has no NumPy form here", depth));
  }
}

}  // namespace

py::array mat_array(const cv::Mat& image) {
  const py::dtype dtype = dtype_of_depth(image.depth());
  std::vector<py::ssize_t> shape{image.rows, image.cols};
  if (image.channels() > 1) shape.push_back(image.channels());
  py::array out(dtype, shape);
  const std::size_t row_bytes = image.cols * image.elemSize();
  auto* to = static_cast<std::uint8_t*>(out.mutable_data());
  for (int r = 0; r < image.rows; ++r) std::memcpy(to + r * row_bytes, image.ptr(r), row_bytes);
  return out;
}

ImageInput::ImageInput(const py::handle& image, std::string role) : role_(std::move(role)), path_(path_argument(image)) {
  name_ = path_ ? *path_ : role_;
  if (!path_) wrapped_ = image_argument(image, role_);
}

cv::Mat ImageInput::read() const { return path_ ? pipeline::read_image(*path_, role_) : wrapped_; }

std::vector<double> double_vector(const py::handle& values, const std::string& role) {
  py::array_t<double, py::array::c_style | py::array::forcecast> array;
  try {
    array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  } catch (const py::error_already_set&) {
    array = {};
  }
  if (!array) throw py::value_error(role + ": expected a sequence of numbers");
  if (array.ndim() != 1) throw py::value_error(fmt::format("{}: expected 1-D values, got {} dimensions", role, array.ndim()));
  return {array.data(), array.data() + array.size()};
}

}  // namespace bosfuse::python
