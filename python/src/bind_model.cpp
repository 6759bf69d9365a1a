// kccd.Model: a loaded model (immutable), its names, and pickling through its YAML text; and the
// NumPy argument checks every binding uses.
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>

#include "bindings.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::python {

namespace {

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

py::array realArray(const py::handle& value, const char* name) {
  py::array a = py::array::ensure(value);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + ": expected an array or a sequence of real numbers");
  }
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(std::string(name) + ": expected real numbers (a float or int dtype), got dtype " +
                         py::str(a.dtype()).cast<std::string>());
  return a;
}

std::vector<std::string> names(const auto& items) {
  std::vector<std::string> out;
  for (const auto& i : items) out.push_back(i.name);
  return out;
}

}  // namespace

std::shared_ptr<ModelHandle> modelFromText(std::string text, std::string source) {
  auto h = std::make_shared<ModelHandle>();
  h->model = std::make_shared<const Model>(parseModel(text, source));
  h->text = std::move(text);
  h->source = std::move(source);
  return h;
}

std::vector<double> stateVector(const py::handle& value, const char* name, int length) {
  const py::array a = realArray(value, name);
  if (a.ndim() != 1 || a.shape(0) != length)
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(length) +
                          ",) (one value per state value, Model.state_names), got " + shapeText(a));
  const auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  return std::vector<double>(d.data(), d.data() + length);
}

namespace {

// `value` as a C-contiguous float64 (rows, cols) array; `rows` and `what` say in the message what
// a row is ("M", "one row per box, ...").
py::array_t<double, py::array::c_style> realMatrix(const py::handle& value, const char* name, int cols,
                                                   const char* rows, const char* what) {
  const py::array a = realArray(value, name);
  if (a.ndim() != 2 || a.shape(1) != cols)
    throw py::value_error(std::string(name) + ": expected shape (" + rows + ", " + std::to_string(cols) + ") (" + what +
                          "), got " + shapeText(a));
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

}  // namespace

py::array_t<double, py::array::c_style> stateMatrix(const py::handle& value, const char* name, int cols) {
  return realMatrix(value, name, cols, "M", "one row per box, one column per state value");
}

py::array_t<double, py::array::c_style> pointMatrix(const py::handle& value, const char* name, int cols) {
  return realMatrix(value, name, cols, "N", "one point per row");
}

void bindModel(py::module_& m) {
  py::class_<ModelHandle, std::shared_ptr<ModelHandle>> model(m, "Model", R"doc(
A robot and its cell: joints, bodies (sphere swept convex hulls) and the checked body pairs.
Immutable. Lengths in metres, angles in radians. Load with Model.load(path) or Model.from_yaml(text).
Pickles through its YAML text (and the file it came from, against which mesh paths resolve).)doc");
  model
      .def_static(
          "load",
          [](const std::string& path) {
            std::string text = readModelText(path);
            return modelFromText(std::move(text), path);
          },
          py::arg("path"), "Reads a `kccd: 1` YAML model file; raises InputError naming the file, line and field.")
      .def_static("from_yaml", &modelFromText, py::arg("text"), py::arg("source") = "<string>",
                  "Parses YAML text; `source` names it in error messages (and is where relative mesh paths resolve).")
      .def_property_readonly(
          "name", [](const ModelHandle& h) { return h.model->name; }, "The model's `name:` from its file.")
      .def_property_readonly(
          "margin", [](const ModelHandle& h) { return h.model->safety_margin; },
          "The safety margin (metres): distances at most this count as a collision.")
      .def_property_readonly(
          "point_budget", [](const ModelHandle& h) { return h.model->point_budget; },
          "The most core points of a first-stage swept volume (`point_budget:`, default 32): it bounds a "
          "query's time; the exact stage refines flagged pairs without it.")
      .def_property_readonly(
          "state_size", [](const ModelHandle& h) { return h.model->stateSize(); },
          "Number of state values (the length of a state, lower or upper).")
      .def_property_readonly(
          "state_names", [](const ModelHandle& h) { return h.model->stateNames(); },
          "The state values in order (`shoulder`, `payload_pose.x`, ...).")
      .def_property_readonly(
          "joints", [](const ModelHandle& h) { return names(h.model->joints); },
          "Joint names, parents before children.")
      .def_property_readonly(
          "bodies", [](const ModelHandle& h) { return names(h.model->bodies); },
          "Body names; QueryResult.pairs' body_a / body_b index this list.")
      .def_property_readonly(
          "pairs",
          [](const ModelHandle& h) {
            std::vector<std::pair<std::string, std::string>> out;
            for (const BodyPair& p : h.model->pairs)
              out.emplace_back(h.model->bodies[static_cast<std::size_t>(p.a)].name,
                               h.model->bodies[static_cast<std::size_t>(p.b)].name);
            return out;
          },
          "The checked pairs (body names), in the order of QueryResult.pairs' pair indices.")
      .def_property_readonly(
          "yaml", [](const ModelHandle& h) { return h.text; }, "The YAML text it was read from.")
      .def_property_readonly(
          "source", [](const ModelHandle& h) { return h.source; },
          "The file it was read from (or the name given to from_yaml).")
      .def(
          "with_body_geometry",
          [](const ModelHandle& h, const std::string& body, const py::handle& points, double radius) {
            const auto p = pointMatrix(points, "points", 3);
            if (p.shape(0) < 1) throw py::value_error("points: expected at least one core point");
            if (!(radius >= 0.0) || !std::isfinite(radius))
              throw py::value_error("radius: must be a finite number >= 0 (metres)");
            // Every digit kept (17 significant digits read back exactly); the radius rounded up.
            std::string flow = "[";
            const auto v = p.unchecked<2>();
            char buf[32];
            for (py::ssize_t i = 0; i < p.shape(0); ++i) {
              flow += i ? ", [" : "[";
              for (int k = 0; k < 3; ++k) {
                if (!std::isfinite(v(i, k))) throw py::value_error("points: must be finite");
                std::snprintf(buf, sizeof buf, "%.17g", v(i, k));
                if (k) flow += ", ";
                flow += buf;
              }
              flow += "]";
            }
            flow += "]";
            const std::string text =
                modelling::withBodyGeometry(h.text, h.source, body, flow, modelling::yamlNumber(radius, true));
            return modelFromText(text, h.source);
          },
          py::arg("body"), py::arg("points"), py::arg("radius"),
          R"doc(A new Model with body `body`'s core points (float64 (K, 3), in its frame, metres) and radius
(metres, written rounded up to 10 significant digits, never smaller) replaced, everything else in the text kept
(comments, order, layout), as `kccd fit --model --body` does; the body's `tolerance` (its old geometry's bound) is
removed. Raises InputError when the body is missing or the edited model does not load.)doc")
      .def("__repr__",
           [](const ModelHandle& h) {
             return "<kccd.Model '" + h.model->name + "': " + std::to_string(h.model->joints.size()) + " joints, " +
                    std::to_string(h.model->bodies.size()) + " bodies, " + std::to_string(h.model->pairs.size()) +
                    " pairs>";
           })
      .def(py::pickle([](const ModelHandle& h) { return py::make_tuple(h.text, h.source); },
                      [](const py::tuple& t) {
                        if (t.size() != 2) throw py::value_error("kccd.Model: bad pickle state");
                        return modelFromText(t[0].cast<std::string>(), t[1].cast<std::string>());
                      }));
}

}  // namespace kccd::python
