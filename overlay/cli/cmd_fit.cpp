// `kccd fit PART --points K`: a conservative SSCH for one rigid part from a CAD file.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::cli {
namespace {

struct FitArgs {
  std::string part_file;
  int points = 8;
  std::string part, name, frame = "world", model, body;
  bool merge = false, json = false, quiet = false, hull = false;
  int evaluations = 4000;
};

Exit runFit(const FitArgs& args) {
  checkCorePoints(args.points);
  if (args.model.empty() != args.body.empty()) throw UsageError("--model and --body go together");
  const auto t0 = std::chrono::steady_clock::now();
  modelling::Part part;
  part = modelling::readPart(args.part_file, {.part = args.part, .merge = args.merge});
  modelling::FitResult r;
  if (args.hull) {
    r = modelling::exactHull(part);
  } else {
    Progress progress("fitting " + std::filesystem::path(args.part_file).filename().string(), args.quiet || args.json);
    r = modelling::fit(part, {.points = args.points,
                              .max_evaluations = args.evaluations,
                              .progress = [&](double f) { progress.update(f); }});
  }
  const std::string points_yaml = modelling::flowPoints(r.points);
  const std::string radius_yaml = modelling::yamlNumber(r.radius, true);  // never smaller than fitted
  const double volume = r.volume;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double hull = r.hull_volume;
  auto ratio = [&](double v) { return hull > 0 ? v / hull : std::numeric_limits<double>::infinity(); };
  const std::string body_name =
      args.name.empty() ? (args.body.empty() ? std::filesystem::path(args.part_file).stem().string() : args.body)
                        : args.name;

  if (!args.model.empty())
    editFile(args.model, [&](const std::string& text) {
      return modelling::withBodyGeometry(text, args.model, args.body, points_yaml, radius_yaml);
    });
  if (args.json) {
    nlohmann::json j;
    j["points"] = nlohmann::json::array();
    for (const Vec3& v : r.points) j["points"].push_back(vec3(v));
    j["radius"] = std::stod(radius_yaml);
    j["volume"] = volume;
    j["hull_volume"] = hull;
    j["volume_ratio"] = number(ratio(volume));
    if (!args.hull)
      j["baselines"] = {{"sphere_volume", r.sphere_volume}, {"sphere_ratio", number(ratio(r.sphere_volume))},
                        {"capsule_volume", r.capsule_volume}, {"capsule_ratio", number(ratio(r.capsule_volume))}};
    j["k"] = static_cast<int>(r.points.size());
    j["exact_hull"] = args.hull;
    j["triangles"] = part.triangles;
    j["primitives"] = part.primitives;
    j["hull_vertices"] = r.hull_vertices;
    j["evaluations"] = r.evaluations;
    j["time_s"] = seconds;
    if (!args.model.empty()) j["written"] = {{"model", args.model}, {"body", args.body}};
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  std::ostringstream out;
  out << "# kccd fit " << args.part_file << ": " << part.triangles << " triangles, " << part.primitives
      << " analytic primitives, " << r.hull_vertices << " hull vertices, " << seconds << " s\n"
      << "# "
      << (args.hull ? "exact convex hull, " + std::to_string(r.points.size()) + " points"
                    : "K = " + std::to_string(args.points))
      << ": volume " << formatNumber(volume, 6) << " = " << formatNumber(ratio(volume), 4) << " x convex hull ("
      << formatNumber(hull, 6) << ")\n";
  if (!args.hull)
    out << "# baselines: bounding sphere (K = 1) " << formatNumber(ratio(r.sphere_volume), 4)
        << " x hull, PCA capsule (K = 2) " << formatNumber(ratio(r.capsule_volume), 4) << " x hull\n";
  if (!args.model.empty()) out << "# written into " << args.model << ", body " << args.body << "\n";
  out << "- name: " << body_name << "\n"
      << "  frame: " << args.frame << "\n"
      << "  points: " << points_yaml << "\n"
      << "  radius: " << radius_yaml << "\n";
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
  sub->add_flag("--hull", args->hull,
                "No fit: the part's exact convex hull (every hull vertex a core point): no looseness, a query "
                "costs more the more vertices (for the links of pairs that work close together)")
      ->excludes(points)
      ->excludes(evaluations);
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
