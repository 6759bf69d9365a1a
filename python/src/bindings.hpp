// The pieces of the `kccd` Python extension (kccd._kccd), one unit per idea, and what they share:
// the model handle every object keeps alive, and NumPy argument checks that name the argument.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "kccd/model.hpp"

namespace kccd::python {

namespace py = pybind11;

/// A loaded model with the text and source it came from (what pickling keeps). Checkers, views
/// and jobs hold the shared model, so it outlives them whatever Python frees first.
struct ModelHandle {
  std::shared_ptr<const Model> model;
  std::string text;    ///< the YAML text
  std::string source;  ///< the file it was read from, or the name given to from_yaml
};

/// `value` as a C-contiguous float64 vector of `length` values: a sequence or an array of real
/// numbers (ints and floats convert; bool, complex, object and text raise TypeError naming `name`;
/// a wrong length raises ValueError naming `name` and the length wanted).
std::vector<double> stateVector(const py::handle& value, const char* name, int length);
/// `value` as a C-contiguous float64 (rows, cols) array, the same checks; `rows` < 0: any.
py::array_t<double, py::array::c_style> stateMatrix(const py::handle& value, const char* name, int cols);

/// `value` as a C-contiguous float64 (N, cols) array of points (pixels, world points), the same checks.
py::array_t<double, py::array::c_style> pointMatrix(const py::handle& value, const char* name, int cols);
/// A handle on the model parsed from `text` (`source` names it in errors). Throws InputError.
std::shared_ptr<ModelHandle> modelFromText(std::string text, std::string source);

void bindErrors(py::module_& m);
void bindModel(py::module_& m);
void bindChecker(py::module_& m);
void bindRender(py::module_& m);
void bindOverlay(py::module_& m);
void bindExplain(py::module_& m);
void bindModelling(py::module_& m);
void bindCalib(py::module_& m);

}  // namespace kccd::python
