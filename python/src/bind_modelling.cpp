// Modelling from Python: kccd.fit (an SSCH fitted to a CAD part or mesh), kccd.import_urdf (a URDF
// to model text) and kccd.prove_pairs (which pairs can never meet, and the ignore list that follows).
#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "arrays.hpp"
#include "bindings.hpp"
#include "kccd/modelling/fit.hpp"
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

void checkPoints(int k) {
  if (k < 1 || k > modelling::kMaxCorePoints)
    throw py::value_error("points: must be 1 ... " + std::to_string(modelling::kMaxCorePoints) + ", got " +
                          std::to_string(k));
}

}  // namespace

void bindModelling(py::module_& m) {
  m.def(
      "fit",
      [](const std::string& path, int k, const std::string& part_name, bool merge, const std::array<double, 3>& scale,
         int max_evaluations, std::uint64_t seed, bool exact_hull, const std::optional<double>& tolerance,
         const py::object& progress) {
        checkPoints(k);
        if (max_evaluations < 1) throw py::value_error("max_evaluations: must be >= 1");
        if (tolerance && !(*tolerance >= 1e-6 && *tolerance <= 1e6))
          throw py::value_error("tolerance: must be a number of millimetres in 1e-6 ... 1e6");
        if (tolerance && exact_hull) throw py::value_error("tolerance: not with exact_hull (the hull has none)");
        ProgressRelay relay{progress, {}};
        modelling::Part part;
        modelling::FitResult r;
        relay.run([&] {
          part = modelling::readPart(path, {.part = part_name, .merge = merge, .scale = {scale[0], scale[1], scale[2]}});
          if (exact_hull) {
            r = modelling::exactHull(part);
          } else if (tolerance) {
            r = modelling::fitToTolerance(part, *tolerance * 1e-3,
                                          {.points = k,
                                           .max_evaluations = max_evaluations,
                                           .seed = seed,
                                           .progress = [&](double f) { relay(f); }});
          } else {
            r = modelling::fit(part, {.points = k,
                                      .max_evaluations = max_evaluations,
                                      .seed = seed,
                                      .progress = [&](double f) { relay(f); }});
          }
        });
        const std::string points_yaml = modelling::flowPoints(r.points);
        const std::string radius_yaml = modelling::yamlNumber(r.radius, true);
        py::dict d;
        d["points"] = pointRows(r.points);
        d["radius"] = std::stod(radius_yaml);
        d["volume"] = r.volume;
        d["hull_volume"] = r.hull_volume;
        d["sphere_volume"] = r.sphere_volume;
        d["capsule_volume"] = r.capsule_volume;
        d["hull_vertices"] = r.hull_vertices;
        d["evaluations"] = r.evaluations;
        d["triangles"] = part.triangles;
        d["primitives"] = part.primitives;
        d["outside"] = r.outside;
        d["method"] = std::string(r.method);
        d["yaml"] = "{points: " + points_yaml + ", radius: " + radius_yaml + "}";
        return d;
      },
      py::arg("part_path"), py::arg("points") = 8, py::kw_only(), py::arg("part") = "", py::arg("merge") = false,
      py::arg("scale") = std::array<double, 3>{1.0, 1.0, 1.0}, py::arg("max_evaluations") = 4000, py::arg("seed") = 1,
      py::arg("exact_hull") = false, py::arg("tolerance") = py::none(), py::arg("progress") = py::none(),
      R"doc(Fits a conservative SSCH (`points` core points, 1 ... 16, and a radius) to a rigid part, as `kccd fit`:
every point of the part lies inside it, and its volume is as small as the search finds. part_path: Open Inventor
(.iv), VRML (.wrl), STL or any mesh Assimp reads (OBJ, COLLADA, PLY, glTF, ...). part: one DEF'd node alone;
merge: accept several top-level parts as one body; scale: per axis, in the file's frame; exact_hull: no fit,
the part's own convex hull (every hull vertex a core point); tolerance: millimetres the volume may reach outside
the part's hull, as `kccd fit --tolerance` (the K = points fit when it meets it, else the fewest hull vertices
that do). progress(fraction) is called with the GIL held.
Returns a dict: 'points' float64 (K, 3) in the part's frame (metres, 10 significant digits), 'radius' (rounded
up: the SSCH still covers the part when written as printed), 'volume', 'hull_volume', 'sphere_volume',
'capsule_volume' (m^3: the fit, the part's hull, and the one-sphere and principal-axis-capsule baselines),
'hull_vertices', 'evaluations', 'triangles', 'primitives', 'outside' (metres: how far the volume may reach
outside the part's hull, an upper bound), 'method' ('fit', 'hull' or 'simplified hull'), and 'yaml' (the body's geometry as a model file
writes it: {points: [...], radius: ...}; see Model.with_body_geometry). Raises InputError naming the file and
place for a part that cannot be read. The GIL is released while fitting.)doc");

  m.def(
      "import_urdf",
      [](const std::string& path, const std::string& srdf, const std::optional<int>& k, double tolerance,
         const py::object& pieces, double concavity, double safety_margin,
         const std::map<std::string, std::string>& packages, bool visuals, bool hulls, bool keep_adjacent,
         const py::object& progress) {
        if (k) checkPoints(*k);
        if (!(tolerance >= 1e-6 && tolerance <= 1e6))
          throw py::value_error("tolerance: must be a number of millimetres in 1e-6 ... 1e6");
        if (!(concavity >= 1e-3 && concavity <= 1e6))
          throw py::value_error("concavity: must be a number of millimetres in 1e-3 ... 1e6");
        int max_pieces = 8;
        if (py::isinstance<py::str>(pieces)) {
          if (pieces.cast<std::string>() != "auto") throw py::value_error("pieces: 'auto' or a number 1 ... 64");
        } else {
          max_pieces = pieces.cast<int>();
          if (max_pieces < 1 || max_pieces > 64) throw py::value_error("pieces: 'auto' or a number 1 ... 64");
        }
        if (!(safety_margin >= 0.0)) throw py::value_error("safety_margin: must be a number >= 0 (metres)");
        ProgressRelay relay{progress, {}};
        std::string text;
        relay.run([&] {
          text = modelling::importUrdf(path, {.srdf = srdf,
                                              .points = k ? *k : 8,
                                              .tolerance = k ? 0.0 : tolerance * 1e-3,
                                              .max_pieces = max_pieces,
                                              .concavity = concavity * 1e-3,
                                              .safety_margin = safety_margin,
                                              .packages = packages,
                                              .visuals = visuals,
                                              .hulls = hulls,
                                              .keep_adjacent = keep_adjacent,
                                              .progress = [&](double f) { relay(f); }});
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
          reports = modelling::provePairs(model, {.margin = margin ? *margin : -1.0,
                                                  .max_boxes = max_boxes,
                                                  .progress = [&](double f) { relay(f); }});
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
          o["ignored"] = r.checked ? py::object(py::none()) : py::object(py::str(modelling::currentIgnoreReason(model, r.a, r.b)));
          const std::string why = modelling::plannedIgnoreReason(plan, model, r.a, r.b);
          o["ignore_reason"] = why.empty() ? py::object(py::none()) : py::object(py::str(why));
          o["bound"] = (r.verdict == modelling::Verdict::Never || r.rigid) ? py::object(py::float_(r.bound)) : py::object(py::none());
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

}  // namespace kccd::python
