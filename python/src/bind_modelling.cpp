// Modelling from Python: kccd.fit (an SSCH fitted to a CAD part or mesh), kccd.import_urdf (a URDF
// to model text) and kccd.prove_pairs (which pairs can never meet, and the ignore list that follows).
#include <pybind11/stl.h>

#include <filesystem>
#include <optional>
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/fit_request.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/part.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "kccd/modelling/yaml_edit.hpp"
#include "progress_relay.hpp"

namespace kccd::python {

namespace {

py::list entries(const std::vector<modelling::IgnoreEntry>& list) {
  py::list out;
  for (const auto& e : list) out.append(py::make_tuple(e.a, e.b, toString(e.reason)));
  return out;
}

// A fit request's check, as ValueError naming the argument (the request's fields are named as
// these functions' arguments are).
void checkRequest(const modelling::FitRequest& request) {
  try {
    modelling::checkFitRequest(request);
  } catch (const modelling::FitRequestError& e) {
    throw py::value_error(e.what());
  }
}

// pieces='auto' (kAutoPieces) or a number.
int piecesArgument(const py::object& pieces) {
  if (py::isinstance<py::str>(pieces)) {
    if (pieces.cast<std::string>() != "auto") throw py::value_error("pieces: 'auto' or a number 1 ... 64");
    return modelling::kAutoPieces;
  }
  if (!py::isinstance<py::int_>(pieces)) throw py::value_error("pieces: 'auto' or a number 1 ... 64");
  return pieces.cast<int>();  // its range checked with the request
}

}  // namespace

namespace {

// One part fitted (kccd fit).
void bindFit(py::module_& m) {
  m.def(
      "fit",
      [](const std::string& path, int k, const std::string& part_name, bool merge, const std::array<double, 3>& scale,
         int max_evaluations, std::uint64_t seed, bool exact_hull, const std::optional<double>& tolerance,
         const py::object& pieces, double concavity, const py::object& progress) {
        if (tolerance && exact_hull) throw py::value_error("tolerance: not with exact_hull (the hull has none)");
        const modelling::FitRequest request{.method = exact_hull  ? modelling::FitMethod::Hull
                                                      : tolerance ? modelling::FitMethod::Tolerance
                                                                  : modelling::FitMethod::Points,
                                            .points = k,
                                            .tolerance = tolerance.value_or(modelling::kDefaultToleranceMm) * 1e-3,
                                            .max_pieces = piecesArgument(pieces),
                                            .concavity = concavity * 1e-3,
                                            .max_evaluations = max_evaluations,
                                            .seed = seed};
        checkRequest(request);
        ProgressRelay relay{progress, {}};
        std::string text;
        relay.run([&] {
          const modelling::Part part =
              modelling::readPart(path, {.part = part_name, .merge = merge, .scale = {scale[0], scale[1], scale[2]}});
          const modelling::FittedPart fitted = modelling::fitPart(part, request, [&](double f) { relay(f); });
          text = modelling::fitJson(part, request, fitted, std::filesystem::path(path).stem().string());
        });
        py::dict d = py::module_::import("json").attr("loads")(text).cast<py::dict>();
        const auto asArray = [](const py::dict& body) {
          body["points"] = py::module_::import("numpy").attr("array")(body["points"], "float64").attr("reshape")(-1, 3);
        };
        if (d.contains("pieces"))
          for (py::handle p : d["pieces"]) asArray(p.cast<py::dict>());
        else
          asArray(d);
        return d;
      },
      py::arg("part_path"), py::arg("points") = 8, py::kw_only(), py::arg("part") = "", py::arg("merge") = false,
      py::arg("scale") = std::array<double, 3>{1.0, 1.0, 1.0}, py::arg("max_evaluations") = 4000, py::arg("seed") = 1,
      py::arg("exact_hull") = false, py::arg("tolerance") = py::none(), py::arg("pieces") = 1,
      py::arg("concavity") = modelling::kDefaultConcavityMm, py::arg("progress") = py::none(),
      R"doc(Fits a conservative SSCH (`points` core points, 1 ... 16, and a radius) to a rigid part, as `kccd fit`:
every point of the part lies inside it, and its volume is as small as the search finds. part_path: Open Inventor
(.iv), VRML (.wrl), STL or any mesh Assimp reads (OBJ, COLLADA, PLY, glTF, ...). part: one DEF'd node alone;
merge: accept several top-level parts as one body; scale: per axis, in the file's frame; seed: of the optimiser's
search directions; exact_hull: no fit, the part's own convex hull (every hull vertex a core point); tolerance:
millimetres the volume may reach outside the part's hull, as `kccd fit --tolerance` (the K = points fit when it
meets it, else the fewest hull vertices that do); pieces: 1 (whole), 'auto' (up to 8) or N: a concave part whose
concavity exceeds `concavity` millimetres splits into convex pieces, as `kccd fit --pieces`. progress(fraction)
is called with the GIL held.
Returns the record `kccd fit --json` prints (docs/formats.md), as a dict: 'points' float64 (K, 3) in the part's
frame (metres, 10 significant digits), 'radius' (rounded up: the SSCH still covers the part when written as
printed), 'volume', 'hull_volume' (m^3), 'volume_ratio', 'baselines' (the one-sphere and principal-axis-capsule
volumes and ratios; not with exact_hull), 'k', 'hull_vertices', 'evaluations', 'outside' (metres: how far the
volume may reach outside the part's hull, an upper bound), 'tolerance' (that bound rounded up to a micrometre,
as a model file records it), 'method' ('fit', 'hull' or 'simplified hull'), 'yaml' (the body's geometry as a
model file writes it: {points: [...], radius: ...}; see Model.with_body_geometry), then 'exact_hull',
'triangles', 'primitives' and, with pieces, 'concavity' (metres). A part split into several pieces has 'pieces':
one such record per piece with its 'name' (FILE/1, FILE/2, ...) and 'concavity', in place of 'points' ... 'yaml'.
Raises ValueError naming the argument out of range, InputError naming the file and place for a part that cannot
be read. The GIL is released while fitting.)doc");
}

// URDF import (kccd import).
void bindImport(py::module_& m) {
  m.def(
      "import_urdf",
      [](const std::string& path, const std::string& srdf, const std::optional<int>& k, double tolerance,
         const py::object& pieces, double concavity, double safety_margin,
         const std::map<std::string, std::string>& packages, bool visuals, bool hulls, bool keep_adjacent,
         const py::object& progress) {
        modelling::ImportOptions options;
        options.srdf = srdf;
        options.fit = {.method = hulls ? modelling::FitMethod::Hull
                                 : k   ? modelling::FitMethod::Points
                                       : modelling::FitMethod::Tolerance,
                       .points = k.value_or(8),
                       .tolerance = tolerance * 1e-3,
                       .max_pieces = piecesArgument(pieces),
                       .concavity = concavity * 1e-3};
        checkRequest(options.fit);
        if (!(safety_margin >= 0.0)) throw py::value_error("safety_margin: must be a number >= 0 (metres)");
        options.safety_margin = safety_margin;
        options.packages = packages;
        options.visuals = visuals;
        options.keep_adjacent = keep_adjacent;
        ProgressRelay relay{progress, {}};
        std::string text;
        relay.run([&] {
          options.progress = [&](double f) { relay(f); };
          text = modelling::importUrdf(path, options);
        });
        return text;
      },
      py::arg("urdf_path"), py::kw_only(), py::arg("srdf") = "", py::arg("points") = py::none(),
      py::arg("tolerance") = modelling::kDefaultToleranceMm, py::arg("pieces") = "auto",
      py::arg("concavity") = modelling::kDefaultConcavityMm, py::arg("safety_margin") = 0.02,
      py::arg("packages") = std::map<std::string, std::string>{}, py::arg("visuals") = true, py::arg("hulls") = false,
      py::arg("keep_adjacent") = false, py::arg("progress") = py::none(),
      R"doc(Converts a URDF into model text (YAML, `kccd: 1`), as `kccd import`: joints and origins one to one, each
link's collision geometry fitted with a conservative SSCH within `tolerance` millimetres of the link's hull (the
fewest points that meet it), or of exactly `points` core points when given (hulls=True: the links' convex hulls,
a tight and slow reference). pieces: 'auto' (up to 8) or N: a link whose concavity exceeds `concavity`
millimetres splits into convex pieces, bodies LINK/1, LINK/2, ... with link: LINK. `pairs: ignore` lists rigidly joined links, adjacent links (unless
keep_adjacent) and the SRDF's disable_collisions (srdf: its path). packages: package:// NAME -> directory.
visuals: write each link's <visual> meshes for drawing. safety_margin: metres. progress(fraction) is called with
the GIL held. Returns the text (kccd.Model.from_yaml(text) loads it; write it to a .yaml file to keep it).
Raises InputError naming the file, line and element on any problem.)doc");
}

// Pair proofs (kccd prove).
void bindProve(py::module_& m) {
  m.def(
      "prove_pairs",
      [](const std::shared_ptr<ModelHandle>& h, const std::optional<double>& margin, int max_boxes, bool keep_adjacent,
         const py::object& progress) {
        const Model& model = *h->model;
        if (margin && !(*margin >= 0.0)) throw py::value_error("margin: must be a number >= 0 (metres)");
        if (max_boxes < 1) throw py::value_error("max_boxes: must be >= 1");
        ProgressRelay relay{progress, {}};
        std::vector<modelling::PairReport> reports;
        relay.run([&] {
          reports = modelling::provePairs(
              model,
              {.margin = margin ? *margin : -1.0, .max_boxes = max_boxes, .progress = [&](double f) { relay(f); }});
        });
        const modelling::IgnorePlan plan = modelling::ignoreList(model, reports, {.keep_adjacent = keep_adjacent});
        py::list pairs;
        for (const auto& r : reports) {
          py::dict o;
          o["a"] = model.bodies[static_cast<std::size_t>(r.a)].name;
          o["b"] = model.bodies[static_cast<std::size_t>(r.b)].name;
          o["frame"] = model.frameName(r.lca);
          o["verdict"] = toString(r.verdict);
          o["adjacent"] = r.adjacent;
          o["rigid"] = r.rigid;
          o["checked"] = r.checked;
          o["boxes"] = r.boxes;
          o["ignored"] =
              r.checked ? py::object(py::none()) : py::object(py::str(modelling::currentIgnoreReason(model, r.a, r.b)));
          const std::string why = modelling::plannedIgnoreReason(plan, model, r.a, r.b);
          o["ignore_reason"] = why.empty() ? py::object(py::none()) : py::object(py::str(why));
          o["bound"] = (r.verdict == modelling::Verdict::Never || r.rigid) ? py::object(py::float_(r.bound))
                                                                           : py::object(py::none());
          if (r.verdict == modelling::Verdict::Meets) {
            o["witness_state"] = floatArray(r.witness);
            o["witness_distance"] = r.witness_distance;
          } else {
            o["witness_state"] = py::none();
            o["witness_distance"] = py::none();
          }
          o["note"] = modelling::verdictNote(r);
          pairs.append(o);
        }
        py::dict out;
        out["margin"] = margin ? *margin : model.safety_margin;
        out["pairs"] = pairs;
        out["ignore"] = entries(plan.ignore);
        out["dropped"] = entries(plan.dropped);
        out["model"] = modelFromText(modelling::withIgnoreList(h->text, h->source, plan.ignore), h->source);
        return out;
      },
      py::arg("model"), py::kw_only(), py::arg("margin") = py::none(), py::arg("max_boxes") = 2000,
      py::arg("keep_adjacent") = false, py::arg("progress") = py::none(),
      R"doc(Proves which body pairs can never come within the margin (metres; None: the model's) over the joint
limits, as `kccd pairs`: branch and bound with the engine's own conservative sweeps, at most max_boxes boxes per
pair. Every pair of bodies in different frames is analysed, checked or not. Returns a dict: 'margin'; 'pairs', a
list of dicts with 'a', 'b', 'frame' (their LCA frame), 'verdict' ('never', 'always_touching', 'meets',
'undecided', 'unbounded'), 'adjacent', 'rigid', 'checked', 'boxes', 'ignored' (the model's reason, or None),
'ignore_reason' (the new list's reason, or None), 'bound' (never or rigid: the smallest lower bound, metres;
else None), 'witness_state' (meets: float64 (state_size,) within the limits where they meet; else None),
'witness_distance' and 'note'; 'ignore' and 'dropped' as (a, b, reason) tuples; 'model', the model with that
ignore list written (everything else in its text kept). progress(fraction) is called with the GIL held.)doc");
}

}  // namespace

void bindModelling(py::module_& m) {
  bindFit(m);
  bindImport(m);
  bindProve(m);
}

}  // namespace kccd::python
