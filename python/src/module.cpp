// The extension module kccd._kccd; the package kccd (python/kccd/__init__.py) re-exports it.
#include "bindings.hpp"

PYBIND11_MODULE(_kccd, m) {
  m.doc() = "KCCD: strictly conservative continuous collision detection for robots (the C++ library's bindings)";
  m.attr("__version__") = KCCD_VERSION_STRING;
  kccd::python::bindErrors(m);
  kccd::python::bindModel(m);
  kccd::python::bindChecker(m);
  kccd::python::bindRender(m);
  kccd::python::bindOverlay(m);
  kccd::python::bindExplain(m);
  kccd::python::bindModelling(m);
  kccd::python::bindCalib(m);
}
