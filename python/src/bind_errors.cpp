// Errors across the boundary: kccd::InputError becomes kccd.InputError (a ValueError) with its
// location as attributes; a missing GL context becomes kccd.GlContextError (a RuntimeError).
#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "kccd/input_error.hpp"
#include "kccd/render/gl_context.hpp"

namespace kccd::python {

void bindErrors(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Input that cannot be used (a model, camera, state log, video, ...). str() is the one-line message "
      "'source[:line[:column]]: field: problem'; .source, .line, .column (1-based, 0: unknown), .field and "
      ".problem give its parts.";
  for (const char* a : {"source", "field", "problem"}) input_error.attr(a) = "";
  input_error.attr("line") = 0;
  input_error.attr("column") = 0;
  static py::exception<render::GlContextError> gl_error(m, "GlContextError", PyExc_RuntimeError);
  gl_error.doc() = "No off-screen GL context could be made (EGL or OSMesa); rendering is not possible here.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      py::object err = py::handle(input_error.ptr())(py::str(e.what()));
      const InputLocation& where = e.location();
      err.attr("source") = where.source;
      err.attr("line") = where.line;
      err.attr("column") = where.column;
      err.attr("field") = where.field;
      err.attr("problem") = e.problem();
      PyErr_SetObject(input_error.ptr(), err.ptr());
    } catch (const render::GlContextError& e) {
      gl_error(e.what());
    }
  });
}

}  // namespace kccd::python
