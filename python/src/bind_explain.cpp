// kccd.explain: what lies behind a flagged pair, off the real-time path: the configuration in the box
// that brings it closest, and whether the flag is a real collision or only a possible one.
#include <pybind11/stl.h>

#include <cmath>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/explain.hpp"

namespace kccd::python {

void bindExplain(py::module_& m) {
  m.def(
      "explain",
      [](const std::shared_ptr<ModelHandle>& h, const py::handle& lower, const py::handle& upper,
         const std::optional<double>& margin, int starts, int max_steps, std::uint64_t seed) {
        const Model& model = *h->model;
        const std::vector<double> lo = stateVector(lower, "lower", model.stateSize());
        const std::vector<double> hi = upper.is_none() ? lo : stateVector(upper, "upper", model.stateSize());
        if (margin && !(*margin >= 0.0)) throw py::value_error("margin: must be a number >= 0 (metres)");
        if (starts < 1) throw py::value_error("starts: must be >= 1");
        if (max_steps < 0) throw py::value_error("max_steps: must be >= 0");
        SearchOptions options;
        options.starts = starts;
        options.max_steps = max_steps;
        options.seed = seed;
        std::vector<PairExplanation> explained;
        {
          py::gil_scoped_release release;
          explained = explainFlagged(model, lo, hi, margin ? *margin : -1.0, options);
        }
        py::list out;
        for (const PairExplanation& e : explained) {
          const BodyPair& p = model.pairs[static_cast<std::size_t>(e.pair)];
          py::dict d;
          d["pair"] = e.pair;
          d["a"] = model.bodies[static_cast<std::size_t>(p.a)].name;
          d["b"] = model.bodies[static_cast<std::size_t>(p.b)].name;
          d["bound"] = e.bound;
          d["distance"] = e.closest.distance;
          d["verdict"] = toString(e.verdict);
          d["state"] = floatArray(e.closest.state);
          d["point_a"] = floatArray({e.closest.point_a.data(), 3});
          d["point_b"] = floatArray({e.closest.point_b.data(), 3});
          d["evaluations"] = e.closest.evaluations;
          out.append(d);
        }
        return out;
      },
      py::arg("model"), py::arg("lower"), py::arg("upper") = py::none(), py::kw_only(), py::arg("margin") = py::none(),
      py::arg("starts") = 12, py::arg("max_steps") = 200, py::arg("seed") = 1,
      R"doc(Explains every pair a distances query flags on the box [lower, upper] (float64 (state_size,) each;
upper None: a point state), as `kccd query --explain`: a list, in pair order, of dicts with 'pair' (index into
Model.pairs), 'a', 'b' (body names), 'bound' (the query's lower bound, metres), 'distance' (the distance at the
closest configuration found: an upper bound on the pair's true minimum), 'verdict' ('real': a configuration
within the margin was found, so the collision is real; 'possible': none was found, the flag may be the bound's
looseness; a local search, not a proof of safety), 'state' float64 (state_size,) (that configuration, inside
the box), 'point_a', 'point_b' float64 (3,) (the closest points, world frame) and 'evaluations'. margin: metres
(None: the model's). starts, max_steps, seed: the search (the same seed gives the same answer). Off the
real-time path: allocates, may take milliseconds per pair; the GIL is released. Raises ValueError for a box a
query refuses (NaN, lower above upper).)doc");
}

}  // namespace kccd::python
