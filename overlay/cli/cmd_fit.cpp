// `kccd fit PART --points K`: a conservative SSCH for one rigid part from a CAD file.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <vector>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_fit_args.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/modelling/convex_hull.hpp"
#include "kccd/modelling/fit_request.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::cli {
namespace {

struct FitArgs {
  std::string part_file;
  int points = 8;
  std::string part, name, frame = "world", model, body;
  bool merge = false, json = false, quiet = false, hull = false;
  int evaluations = 4000;
  std::uint64_t seed = 1;
  std::vector<double> scale = {1.0, 1.0, 1.0};
  double tolerance_mm = 0.0;  // > 0: the fewest points meeting it (--tolerance)
  std::string pieces = "1";
  double concavity_mm = modelling::kDefaultConcavityMm;
};

// The request the options make (checked, options named).
modelling::FitRequest fitRequest(const FitArgs& args) {
  const modelling::FitRequest r{.method = args.hull               ? modelling::FitMethod::Hull
                                          : args.tolerance_mm > 0 ? modelling::FitMethod::Tolerance
                                                                  : modelling::FitMethod::Points,
                                .points = args.points,
                                .tolerance = args.tolerance_mm * 1e-3,
                                .max_pieces = piecesOption(args.pieces),
                                .concavity = args.concavity_mm * 1e-3,
                                .max_evaluations = args.evaluations,
                                .seed = args.seed};
  checkFitOptions(r);
  return r;
}

Exit runFit(const FitArgs& args) {
  const modelling::FitRequest request = fitRequest(args);
  if (args.model.empty() != args.body.empty()) throw UsageError("--model and --body go together");
  if (args.scale.size() == 1 || args.scale.size() == 3) {
    for (const double v : args.scale)
      if (!std::isfinite(v) || v == 0.0) throw UsageError("--scale: each factor must be a finite number other than 0");
  } else {
    throw UsageError("--scale: give one factor or three (X,Y,Z)");
  }
  const Vec3 scale =
      args.scale.size() == 1 ? Vec3::Constant(args.scale[0]) : Vec3(args.scale[0], args.scale[1], args.scale[2]);
  const auto t0 = std::chrono::steady_clock::now();
  const modelling::Part part =
      modelling::readPart(args.part_file, {.part = args.part, .merge = args.merge, .scale = scale});
  modelling::FittedPart fitted;
  {
    Progress progress("fitting " + std::filesystem::path(args.part_file).filename().string(),
                      args.quiet || args.json || args.hull);
    fitted = modelling::fitPart(part, request, [&](double f) { progress.update(f); });
  }
  const int count = static_cast<int>(fitted.pieces.size());
  if (count > 1 && !args.model.empty())
    throw UsageError("--model replaces one body, but " + args.part_file + " splits into " + std::to_string(count) +
                     " pieces (--pieces 1 fits it whole; kccd import writes a link's pieces)");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string stem = args.name.empty()
                               ? (args.body.empty() ? std::filesystem::path(args.part_file).stem().string() : args.body)
                               : args.name;
  auto nameOf = [&](int k) { return modelling::pieceName(stem, k, count); };
  const auto fitOf = [&](int k) -> const modelling::FitResult& {
    return fitted.pieces[static_cast<std::size_t>(k)].fit;
  };

  if (!args.model.empty()) {
    const modelling::FitResult& r = fitOf(0);
    editFile(args.model, [&](const std::string& text) {
      return modelling::withBodyGeometry(text, args.model, args.body, modelling::flowPoints(r.points),
                                         modelling::yamlNumber(r.radius, true), modelling::toleranceYaml(r));
    });
  }
  if (args.json) {
    nlohmann::json j = nlohmann::json::parse(modelling::fitJson(part, request, fitted, stem));
    j["time_s"] = seconds;
    if (!args.model.empty()) j["written"] = {{"model", args.model}, {"body", args.body}};
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  std::ostringstream out;
  out << "# kccd fit " << args.part_file << ": " << part.triangles << " triangles, " << part.primitives
      << " analytic primitives, "
      << (count == 1 ? fitOf(0).hull_vertices : static_cast<int>(modelling::convexHull(part.samples()).vertices.size()))
      << " hull vertices, " << seconds << " s\n";
  if (fitted.measured)
    out << "# concavity " << formatNumber(fitted.whole_concavity * 1e3, 3) << " mm"
        << (count > 1 ? ": " + std::to_string(count) + " convex pieces" : std::string(", one piece")) << "\n";
  for (int k = 0; k < count; ++k) {
    const modelling::FitResult& r = fitOf(k);
    const double hull = r.hull_volume;
    auto ratio = [&](double v) { return hull > 0 ? v / hull : std::numeric_limits<double>::infinity(); };
    out << "# " << (count > 1 ? nameOf(k) + ": " : "")
        << (args.hull               ? "exact convex hull, " + std::to_string(r.points.size()) + " points"
            : args.tolerance_mm > 0 ? std::string(r.method) + ", " + std::to_string(r.points.size()) + " points"
                                    : "K = " + std::to_string(args.points))
        << ": volume " << formatNumber(r.volume, 6) << " = " << formatNumber(ratio(r.volume), 4) << " x convex hull ("
        << formatNumber(hull, 6) << "), at most " << formatNumber(r.outside * 1e3, 3) << " mm outside it\n";
    if (!args.hull && count == 1)
      out << "# baselines: bounding sphere (K = 1) " << formatNumber(ratio(r.sphere_volume), 4)
          << " x hull, PCA capsule (K = 2) " << formatNumber(ratio(r.capsule_volume), 4) << " x hull\n";
  }
  if (!args.model.empty()) out << "# written into " << args.model << ", body " << args.body << "\n";
  for (int k = 0; k < count; ++k)
    out << modelling::bodyYaml(
        {.name = nameOf(k), .link = count > 1 ? stem : std::string(), .frame = args.frame, .fit = &fitOf(k)});
  std::cout << out.str();
  return Exit::Ok;
}

}  // namespace

Runner addFit(CLI::App& app) {
  auto args = std::make_shared<FitArgs>();
  CLI::App* sub = app.add_subcommand(
      "fit",
      "Fits a conservative SSCH (K core points + radius) to one rigid part from an Open Inventor (.iv, ASCII or "
      "binary) or VRML 1/2 (.wrl) file (Coin3D), or a mesh: STL, OBJ, COLLADA (.dae), PLY, glTF (.glb, .gltf) and "
      "the other formats Assimp reads; every point of the part is inside, the volume is minimised");
  sub->add_option("part", args->part_file, "CAD file of the part")->required();
  CLI::Option* points =
      sub->add_option("--points,-k", args->points, "Number of core points K (1 ... 16)")->capture_default_str();
  sub->add_option("--part", args->part, "Fit only the node DEF'd with this name");
  sub->add_flag("--merge", args->merge, "Fit all top-level parts of the file as one rigid body");
  sub->add_option("--name", args->name, "Body name in the printed snippet (default: the file name)");
  sub->add_option("--frame", args->frame, "Frame in the printed snippet")->capture_default_str();
  sub->add_option("--model", args->model, "Write the result into this model file, in place (with --body)");
  sub->add_option("--body", args->body, "Body of --model whose points and radius are replaced");
  CLI::Option* evaluations =
      sub->add_option("--evaluations", args->evaluations,
                      "Optimiser budget per start (volume evaluations; three starts are refined)")
          ->capture_default_str()
          ->check(CLI::Range(1, 10000000));
  sub->add_option("--seed", args->seed, "Seed of the optimiser's random search directions")
      ->capture_default_str()
      ->check(seedNumber());
  sub->add_option("--scale", args->scale,
                  "Scale of the part in its file's frame: one factor, or three (X,Y,Z), as a URDF mesh's scale (e.g. "
                  "0.001 for a "
                  "part drawn in millimetres)")
      ->delimiter(',')
      ->expected(1, 3)
      ->default_str("1");
  sub->add_flag("--hull", args->hull,
                "No fit: the part's exact convex hull (every hull vertex a core point): no looseness, a query "
                "costs more the more vertices (for the links of pairs that work close together)")
      ->excludes(points)
      ->excludes(evaluations);
  sub->add_option("--tolerance", args->tolerance_mm,
                  "Millimetres the volume may reach outside the part's convex hull: the fewest points that meet it "
                  "(the K fit when it does, else hull vertices added farthest first)")
      ->check(finiteIn(1e-6, 1e6))
      ->excludes("--hull");
  addPieceOptions(*sub, args->pieces, args->concavity_mm,
                  "A concave part (each piece a body NAME/1, NAME/2, ... with link: NAME)");
  sub->add_flag("--json", args->json, "Machine-readable output");
  sub->add_flag("--quiet,-q", args->quiet, "No progress display");
  sub->footer(
      "Spheres, cylinders and cones are covered analytically (circumscribed, never Coin's inscribed "
      "tessellation); the radius is recomputed exactly for the printed points. Meshes: every node transform "
      "applied; COLLADA's <unit meter> applied, its <up_axis> not (coordinates as written, as ROS tools place "
      "them); --part picks a node by name.\n"
      "Exit status: 0 done, 2 bad input.");
  return [args] { return runFit(*args); };
}

}  // namespace kccd::cli
