// Results out as NumPy arrays (arrays.hpp).
#include "arrays.hpp"

#include <algorithm>
#include <cstring>

namespace kccd::python {

py::array_t<double> floatArray(std::span<const double> values) {
  py::array_t<double> out(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

py::array_t<double> pointRows(std::span<const Vec3> points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int k = 0; k < 3; ++k) o(static_cast<py::ssize_t>(i), k) = points[i][k];
  return out;
}

py::array_t<std::uint8_t> imageArray(const cv::Mat& image) {
  std::vector<py::ssize_t> shape{image.rows, image.cols};
  if (image.channels() > 1) shape.push_back(image.channels());
  py::array_t<std::uint8_t> out(shape);
  const std::size_t row = static_cast<std::size_t>(image.cols) * static_cast<std::size_t>(image.channels());
  for (int r = 0; r < image.rows; ++r)
    std::memcpy(out.mutable_data() + static_cast<std::size_t>(r) * row, image.ptr(r), row);
  return out;
}

}  // namespace kccd::python
