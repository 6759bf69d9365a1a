// kccd.Checker: queries over interval boxes, one at a time (query) or many in C++ with the GIL
// released (query_many, optionally on several threads with a Checker each); kccd.Status (an
// enum.IntEnum); braking intervals.
#include <pybind11/stl.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <thread>

#include "bindings.hpp"
#include "kccd/braking.hpp"
#include "kccd/checker.hpp"

namespace kccd::python {

namespace {

// What a query asks, from the Python arguments (as `kccd query`'s options).
QueryOptions makeOptions(const Model& model, const std::string& type, int n, const py::object& margin,
                         const py::object& exact, double budget_us) {
  QueryOptions o;
  const std::optional<QueryType> t = queryTypeFromString(type);
  if (!t) throw py::value_error("type: expected 'collision', 'closest', 'nclosest' or 'distances', got '" + type + "'");
  o.type = *t;
  if (n < 1) throw py::value_error("n: expected at least 1, got " + std::to_string(n));
  o.n = n;
  if (!margin.is_none()) {
    const double mg = margin.cast<double>();
    if (!(mg >= 0.0 && mg <= kMaxModelLength)) throw py::value_error("margin: expected metres from 0 to 1e6");
    o.margin = mg;
  }
  const double mg = o.margin >= 0.0 ? o.margin : model.safety_margin;
  if (exact.is_none()) {
  } else if (py::isinstance<py::str>(exact)) {
    const std::string e = exact.cast<std::string>();
    const std::optional<double> below = exactBelowFromWord(e, mg);
    if (!below) throw py::value_error("exact: expected 'band', 'margin', 'all', 'off' or metres, got '" + e + "'");
    o.exact_below = *below;
  } else {
    const double d = exact.cast<double>();
    if (!(d >= 0.0 && d <= kMaxModelLength)) throw py::value_error("exact: expected metres from 0 to 1e6");
    o.exact_below = d;
  }
  o.budget_us = budget_us;
  return o;
}

// A query's answer copied out of the checker's buffers; its NumPy arrays (fresh, never views of
// the checker) are made on first access, so a query that only reads the verdict pays for none.
struct PyResult {
  int status = 0;
  QueryType type = QueryType::Collision;
  bool collision = true;
  double min_distance = 0.0, margin = 0.0;
  QueryStats stats;
  std::vector<PairDistance> pairs;
  std::shared_ptr<ModelHandle> model;
  py::object arrays;  // a tuple of the arrays below, once made

  enum Field { kPair, kBodyA, kBodyB, kDistance, kWitnessA, kWitnessB, kFresh, kHasWitness };
  py::object array(Field f) {
    if (!arrays) arrays = makeArrays();
    return arrays[py::int_(static_cast<int>(f))];
  }

 private:
  py::tuple makeArrays() const {
    const auto n = static_cast<py::ssize_t>(pairs.size());
    py::array_t<std::int32_t> pair(n), body_a(n), body_b(n);
    py::array_t<double> distance(n), witness_a({n, py::ssize_t{3}}), witness_b({n, py::ssize_t{3}});
    py::array_t<bool> fresh(n), has_witness(n);
    auto pr = pair.mutable_unchecked<1>();
    auto ba = body_a.mutable_unchecked<1>();
    auto bb = body_b.mutable_unchecked<1>();
    auto di = distance.mutable_unchecked<1>();
    auto wa = witness_a.mutable_unchecked<2>();
    auto wb = witness_b.mutable_unchecked<2>();
    auto fr = fresh.mutable_unchecked<1>();
    auto hw = has_witness.mutable_unchecked<1>();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (py::ssize_t i = 0; i < n; ++i) {
      const PairDistance& p = pairs[static_cast<std::size_t>(i)];
      const BodyPair& bp = model->model->pairs[static_cast<std::size_t>(p.pair)];
      pr(i) = p.pair;
      ba(i) = bp.a;
      bb(i) = bp.b;
      di(i) = p.distance;
      for (int k = 0; k < 3; ++k) {
        wa(i, k) = p.has_witness ? p.witness_a[k] : nan;
        wb(i, k) = p.has_witness ? p.witness_b[k] : nan;
      }
      fr(i) = p.fresh;
      hw(i) = p.has_witness;
    }
    return py::make_tuple(pair, body_a, body_b, distance, witness_a, witness_b, fresh, has_witness);
  }
};

// kccd.Status's members by value, made once by bindChecker (kept for the interpreter's life).
std::vector<PyObject*> g_status;
py::object statusObject(int value) {
  return py::reinterpret_borrow<py::object>(g_status[static_cast<std::size_t>(value)]);
}

PyResult copyResult(const std::shared_ptr<ModelHandle>& model, const QueryResult& r) {
  PyResult out;
  out.status = static_cast<int>(r.status);
  out.type = r.type;
  out.collision = r.collision;
  out.min_distance = r.min_distance;
  out.margin = r.margin;
  out.stats = r.stats;
  out.pairs.assign(r.pairs.begin(), r.pairs.end());
  out.model = model;
  return out;
}

py::dict statsDict(const QueryStats& s) {
  py::dict d;
  d["time_us"] = s.time_us;
  d["pairs_checked"] = s.pairs_checked;
  d["gjk_calls"] = s.gjk_calls;
  d["gjk_iterations"] = s.gjk_iterations;
  d["exact_calls"] = s.exact_calls;
  d["split_pairs"] = s.split_pairs;
  d["volumes_swept"] = s.volumes_swept;
  d["budget_exhausted"] = s.budget_exhausted;
  return d;
}

// A Checker with its model kept alive and a guard against use from two threads at once.
class PyChecker {
 public:
  PyChecker(std::shared_ptr<ModelHandle> model, const py::object& budget_us)
      : handle_(std::move(model)), checker_(*handle_->model) {
    if (!budget_us.is_none()) {
      budget_us_ = budget_us.cast<double>();
      if (!(budget_us_ > 0.0)) throw py::value_error("budget_us: expected a positive number of microseconds, or None");
    }
  }

  PyResult query(const py::object& lower, const py::object& upper, const std::string& type, int n,
                 const py::object& margin, const py::object& exact) {
    const Model& m = *handle_->model;
    const QueryOptions o = makeOptions(m, type, n, margin, exact, budget_us_);
    const std::vector<double> lo = stateVector(lower, "lower", m.stateSize());
    const std::vector<double> hi = upper.is_none() ? lo : stateVector(upper, "upper", m.stateSize());
    Guard guard(busy_);
    const QueryResult* r = nullptr;
    {
      py::gil_scoped_release release;
      r = &checker_.query(lo, hi, o);
    }
    return copyResult(handle_, *r);
  }

  py::dict queryMany(const py::object& lowers, const py::object& uppers, const std::string& type, int n,
                     const py::object& margin, const py::object& exact, int threads, bool reuse) {
    const Model& m = *handle_->model;
    const QueryOptions o = makeOptions(m, type, n, margin, exact, budget_us_);
    const auto lo = stateMatrix(lowers, "lowers", m.stateSize());
    const auto hi = uppers.is_none() ? lo : stateMatrix(uppers, "uppers", m.stateSize());
    if (hi.shape(0) != lo.shape(0))
      throw py::value_error("uppers: expected as many rows as lowers (" + std::to_string(lo.shape(0)) + "), got " +
                            std::to_string(hi.shape(0)));
    if (threads < 1) throw py::value_error("threads: expected at least 1");
    const py::ssize_t rows = lo.shape(0);
    const auto nsz = static_cast<std::size_t>(m.stateSize());
    py::array_t<std::int8_t> status(rows);
    py::array_t<bool> collision(rows);
    py::array_t<double> min_distance(rows);
    std::int8_t* st = status.mutable_data();
    bool* co = collision.mutable_data();
    double* md = min_distance.mutable_data();
    const double* lp = lo.data();
    const double* hp = hi.data();
    Guard guard(busy_);
    {
      py::gil_scoped_release release;
      auto run = [&](Checker& c, py::ssize_t begin, py::ssize_t end) {
        for (py::ssize_t i = begin; i < end; ++i) {
          if (!reuse) c.reset();
          const auto off = static_cast<std::size_t>(i) * nsz;
          const QueryResult& r = c.query({lp + off, nsz}, {hp + off, nsz}, o);
          st[i] = static_cast<std::int8_t>(r.status);
          co[i] = r.collision;
          md[i] = r.min_distance;
        }
      };
      const int used = static_cast<int>(std::min<py::ssize_t>(threads, std::max<py::ssize_t>(rows, 1)));
      if (used <= 1) {
        run(checker_, 0, rows);
      } else {
        std::vector<std::thread> pool;
        std::vector<std::unique_ptr<Checker>> checkers;
        for (int t = 1; t < used; ++t) checkers.push_back(std::make_unique<Checker>(m));
        auto range = [&](int t) { return std::pair<py::ssize_t, py::ssize_t>{rows * t / used, rows * (t + 1) / used}; };
        for (int t = 1; t < used; ++t)
          pool.emplace_back(
              [&, t] { run(*checkers[static_cast<std::size_t>(t - 1)], range(t).first, range(t).second); });
        run(checker_, range(0).first, range(0).second);
        for (std::thread& th : pool) th.join();
      }
    }
    py::dict out;
    out["status"] = status;
    out["collision"] = collision;
    out["min_distance"] = min_distance;
    return out;
  }

  void reset() {
    Guard guard(busy_);
    checker_.reset();
  }
  const std::shared_ptr<ModelHandle>& model() const { return handle_; }
  py::object budget() const { return budget_us_ > 0.0 ? py::cast(budget_us_) : py::none(); }

 private:
  // Marks the checker busy for one call; a second thread's call raises instead of corrupting it.
  struct Guard {
    explicit Guard(std::atomic<bool>& b) : busy(b) {
      bool expected = false;
      if (!busy.compare_exchange_strong(expected, true))
        throw std::runtime_error(
            "kccd.Checker: used from two threads at once; give each thread its own Checker (or use "
            "query_many(threads=N))");
    }
    ~Guard() { busy.store(false); }
    std::atomic<bool>& busy;
  };
  std::shared_ptr<ModelHandle> handle_;
  Checker checker_;
  double budget_us_ = 0.0;
  std::atomic<bool> busy_{false};
};

}  // namespace

void bindChecker(py::module_& m) {
  py::list members;
  const std::pair<const char*, Status> names[] = {{"OK", Status::Ok},
                                                  {"WRONG_STATE_SIZE", Status::WrongStateSize},
                                                  {"NON_FINITE_STATE", Status::NonFiniteState},
                                                  {"LOWER_ABOVE_UPPER", Status::LowerAboveUpper},
                                                  {"EXACT_NEEDS_POINT", Status::ExactNeedsPoint},
                                                  {"NUMERICAL_FAILURE", Status::NumericalFailure}};
  for (const auto& [name, s] : names) members.append(py::make_tuple(name, static_cast<int>(s)));
  py::object status = py::module_::import("enum").attr("IntEnum")("Status", members, py::arg("module") = "kccd");
  status.attr("__doc__") =
      "A query's outcome. Anything but OK means 'unsafe, stop' (the answer counts as a collision).";
  m.attr("Status") = status;
  for (const auto& [name, s] : names) g_status.push_back(status(static_cast<int>(s)).inc_ref().ptr());

  py::class_<PyResult>(m, "QueryResult", "One query's answer: every distance is a lower bound over the whole box.")
      .def_property_readonly(
          "status", [](const PyResult& r) { return statusObject(r.status); }, "kccd.Status; anything but OK is unsafe")
      .def_property_readonly(
          "type", [](const PyResult& r) { return toString(r.type); },
          "'collision', 'closest', 'nclosest' or 'distances'")
      .def_readonly("collision", &PyResult::collision,
                    "Some pair's bound is within the margin (or the status is not OK).")
      .def_readonly("min_distance", &PyResult::min_distance,
                    "Smallest lower bound over all pairs (metres; inf without pairs).")
      .def_readonly("margin", &PyResult::margin, "The margin used (metres).")
      .def_property_readonly(
          "pair", [](PyResult& r) { return r.array(PyResult::kPair); },
          "int32 (N,): index into Model.pairs of each reported pair")
      .def_property_readonly(
          "body_a", [](PyResult& r) { return r.array(PyResult::kBodyA); }, "int32 (N,): index into Model.bodies")
      .def_property_readonly(
          "body_b", [](PyResult& r) { return r.array(PyResult::kBodyB); }, "int32 (N,): index into Model.bodies")
      .def_property_readonly(
          "distance", [](PyResult& r) { return r.array(PyResult::kDistance); },
          "float64 (N,): lower bound over the box (metres)")
      .def_property_readonly(
          "witness_a", [](PyResult& r) { return r.array(PyResult::kWitnessA); },
          "float64 (N, 3): closest points found, in the pair's common-ancestor frame (NaN without a witness)")
      .def_property_readonly(
          "witness_b", [](PyResult& r) { return r.array(PyResult::kWitnessB); },
          "float64 (N, 3): as witness_a, on body b")
      .def_property_readonly(
          "fresh", [](PyResult& r) { return r.array(PyResult::kFresh); },
          "bool (N,): recomputed in this query (else carried over from earlier ones)")
      .def_property_readonly(
          "has_witness", [](PyResult& r) { return r.array(PyResult::kHasWitness); },
          "bool (N,): witness points are valid")
      .def_property_readonly(
          "stats", [](const PyResult& r) { return statsDict(r.stats); },
          "time_us, pairs_checked, gjk_calls, gjk_iterations, exact_calls, split_pairs, volumes_swept, "
          "budget_exhausted")
      .def("__len__", [](const PyResult& r) { return r.pairs.size(); })
      .def("__repr__", [](const PyResult& r) {
        return "<kccd.QueryResult " + py::str(statusObject(r.status).attr("name")).cast<std::string>() + " " +
               toString(r.type) + (r.collision ? " collision" : " clear") +
               " min_distance=" + std::to_string(r.min_distance) + " pairs=" + std::to_string(r.pairs.size()) + ">";
      });

  py::class_<PyChecker>(m, "Checker", R"doc(
Answers queries over interval boxes (one interval per state value). Keeps swept volumes and the
bounds of earlier queries, which stay valid lower bounds and speed up the next cycle. Not for two
threads at once (that raises RuntimeError): one Checker per thread.)doc")
      .def(py::init<std::shared_ptr<ModelHandle>, py::object>(), py::arg("model"), py::arg("budget_us") = py::none(),
           "A checker for `model`; `budget_us`: time budget per query in microseconds (None: unlimited).")
      .def("query", &PyChecker::query, py::arg("lower"), py::arg("upper") = py::none(), py::kw_only(),
           py::arg("type") = "collision", py::arg("n") = 1, py::arg("margin") = py::none(),
           py::arg("exact") = py::none(),
           R"doc(One query over the box [lower, upper] (float64 (state_size,), radians / metres in Model.state_names
order; upper None: the single configuration `lower`). type: 'collision' | 'closest' | 'nclosest' (n pairs) |
'distances'. margin: metres (None: the model's). exact: which pairs the exact stage refines, as `kccd query
--exact`: 'band' (default), 'margin', 'all', 'off' or metres. The GIL is released during the query.)doc")
      .def(
          "query_many", &PyChecker::queryMany, py::arg("lowers"), py::arg("uppers") = py::none(), py::kw_only(),
          py::arg("type") = "collision", py::arg("n") = 1, py::arg("margin") = py::none(),
          py::arg("exact") = py::none(), py::arg("threads") = 1, py::arg("reuse") = false,
          R"doc(Queries M boxes (lowers, uppers: float64 (M, state_size)) in C++ with the GIL released; returns a dict of
fresh arrays: 'status' int8 (M,) (kccd.Status values), 'collision' bool (M,), 'min_distance' float64 (M,).
threads: split the rows over this many threads, each with its own Checker. reuse: keep bounds from row to
row (consecutive cycles of one robot); False (default): every row answered as by a new Checker.)doc")
      .def("reset", &PyChecker::reset, "Forgets every stored bound: the next answer is exactly a new Checker's.")
      .def_property_readonly("model", &PyChecker::model, "The Model this checker queries.")
      .def_property_readonly("budget_us", &PyChecker::budget,
                             "The time budget per query in microseconds, or None when unlimited. A query whose "
                             "budget runs out is still conservative: pairs it never computed count as 0.");

  py::class_<BrakingParams>(m, "BrakingParams", "Braking of one state value (SI units: m or rad, per s, per s^2).")
      .def(py::init([](double position_error, double velocity_error, double latency, double max_acceleration,
                       double deceleration) {
             return BrakingParams{position_error, velocity_error, latency, max_acceleration, deceleration};
           }),
           py::kw_only(), py::arg("position_error") = 0.0, py::arg("velocity_error") = 0.0, py::arg("latency") = 0.0,
           py::arg("max_acceleration") = 0.0, py::arg("deceleration") = 1.0)
      .def_readwrite("position_error", &BrakingParams::position_error,
                     "Bound on the position measurement error (m or rad; 0 ... 1e3).")
      .def_readwrite("velocity_error", &BrakingParams::velocity_error,
                     "Bound on the velocity measurement error (m/s or rad/s; 0 ... 1e6).")
      .def_readwrite(
          "latency", &BrakingParams::latency,
          "Reaction latency in seconds (0 ... 1e3): one full control cycle plus delays, before braking starts.")
      .def_readwrite("max_acceleration", &BrakingParams::max_acceleration,
                     "Worst-case acceleration during the latency (m/s^2 or rad/s^2; 0 ... 1e9).")
      .def_readwrite("deceleration", &BrakingParams::deceleration,
                     "Guaranteed braking deceleration (m/s^2 or rad/s^2; 1e-9 ... 1e9, more than 0).");

  m.def(
      "braking_intervals",
      [](const std::shared_ptr<ModelHandle>& h, const py::object& q, const py::object& v, const py::object& params) {
        const Model& model = *h->model;
        const int n = model.stateSize();
        const std::vector<double> qs = stateVector(q, "q", n), vs = stateVector(v, "v", n);
        std::vector<BrakingParams> ps;
        if (py::isinstance<BrakingParams>(params)) {
          ps.assign(static_cast<std::size_t>(n), params.cast<BrakingParams>());
        } else {
          ps = params.cast<std::vector<BrakingParams>>();
          if (static_cast<int>(ps.size()) != n)
            throw py::value_error("params: expected one BrakingParams or one per state value (" + std::to_string(n) +
                                  ")");
        }
        py::array_t<double> lower(n), upper(n);
        if (!brakingIntervals(model, qs, vs, ps, {lower.mutable_data(), static_cast<std::size_t>(n)},
                              {upper.mutable_data(), static_cast<std::size_t>(n)}))
          throw py::value_error("braking_intervals: non-finite q or v, or a deceleration <= 0");
        return py::make_tuple(lower, upper);
      },
      py::arg("model"), py::arg("q"), py::arg("v"), py::arg("params"),
      R"doc(The box of every stop if braking starts now: (lower, upper) float64 (state_size,) from positions q and
velocities v (state order), clamped to the joint limits. params: one BrakingParams for every value, or one each.)doc");
}

}  // namespace kccd::python
