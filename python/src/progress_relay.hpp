// Progress callbacks from long C++ jobs back into Python: called with the GIL held, and an
// exception the callback raises stops the job and is raised again in Python.
#pragma once
#include <pybind11/pybind11.h>

#include <optional>
#include <utility>

namespace kccd::python {

namespace py = pybind11;

/// Thrown through a job when its progress callback raised: the job stops and writes nothing.
struct CallbackRaised {};

/// Relays a job's progress to a Python callable (None: no calls). run() runs the job with the GIL
/// released and raises the callback's exception if it stopped the job.
struct ProgressRelay {
  py::object callback;
  std::optional<py::error_already_set> error;

  template <class... A>
  void operator()(A... args) {
    if (callback.is_none()) return;
    py::gil_scoped_acquire gil;
    try {
      callback(args...);
    } catch (py::error_already_set& e) {
      error = std::move(e);
      throw CallbackRaised{};
    }
  }

  template <class F>
  void run(F&& job) {
    try {
      py::gil_scoped_release release;
      job();
    } catch (const CallbackRaised&) {
      throw std::move(*error);
    }
  }
};

}  // namespace kccd::python
