// Results out as NumPy arrays: fresh, C-contiguous copies that own their data (never views of a
// C++ buffer), shared by every binding unit.
#pragma once
#include <pybind11/numpy.h>

#include <cstdint>
#include <span>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "kccd/types.hpp"

namespace kccd::python {

namespace py = pybind11;

/// `values` as a float64 (N,) array.
py::array_t<double> floatArray(std::span<const double> values);
/// `points` as a float64 (N, 3) array, one point per row.
py::array_t<double> pointRows(std::span<const Vec3> points);
/// An 8-bit image as a uint8 (H, W) array (one channel) or (H, W, C), channels as stored.
py::array_t<std::uint8_t> imageArray(const cv::Mat& image);

}  // namespace kccd::python
