#pragma once
// NumPy arrays in and out of the bindings. An image comes in as a 2-D
// C-contiguous array of uint8, uint16 or float32 (wrapped, not copied: the
// cv::Mat shares its pixels, so the caller keeps the array alive while the
// Mat is used) or as a path OpenCV reads; anything else is a ValueError
// naming the argument and what was wrong. Results go out as new arrays.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace bosfuse::python {

// `role` names the argument in messages ("reference", "mask").
cv::Mat image_argument(const pybind11::handle& image, const std::string& role);
// An image argument taken in two steps, so that a file is read with the
// GIL released: the constructor (GIL held) wraps an array or notes a path,
// read() (GIL released or held) gives the pixels, reading the file then.
class ImageInput {
 public:
  ImageInput(const pybind11::handle& image, std::string role);
  cv::Mat read() const;
  const std::string& name() const { return name_; }  // the path, or the role for an array

 private:
  std::string role_, name_;
  std::optional<std::string> path_;
  cv::Mat wrapped_;
};

// A path (str or os.PathLike) as text; nothing when `value` is not one.
std::optional<std::string> path_argument(const pybind11::handle& value);

// A rows × cols array filled by `value(i)` for element i in row-major order.
template <typename T, typename F>
pybind11::array_t<T> grid_array(int rows, int cols, F value) {
  pybind11::array_t<T> out({rows, cols});
  T* data = out.mutable_data();
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  for (std::size_t i = 0; i < n; ++i) data[i] = static_cast<T>(value(i));
  return out;
}

// A 1-D array of `values`.
template <typename T>
pybind11::array_t<T> vector_array(const std::vector<T>& values) {
  pybind11::array_t<T> out(static_cast<pybind11::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

// A copy of `image` (8 or 16 bit, float32 or float64; one channel or
// several) as a new array shaped (rows, cols) or (rows, cols, channels):
// the depth it has, not converted.
pybind11::array mat_array(const cv::Mat& image);

// A 1-D float64 array as a vector; ValueError naming `role` when it is not
// 1-D or not numbers.
std::vector<double> double_vector(const pybind11::handle& values, const std::string& role);

}  // namespace bosfuse::python
