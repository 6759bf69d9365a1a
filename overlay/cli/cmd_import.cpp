// `kccd import URDF`: a KCCD model from a URDF (and SRDF), collision geometry fitted with SSCHs.
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_fit_args.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::cli {
namespace {

struct ImportArgs {
  std::string urdf, srdf, output;
  int points = 8;
  double margin = 0.02;
  std::vector<std::string> packages;
  bool quiet = false, pairs = false, no_visuals = false, keep_adjacent = false, hulls = false;
  int max_boxes = 2000;
  double tolerance_mm = modelling::kDefaultToleranceMm;
  std::string pieces = "auto";
  double concavity_mm = modelling::kDefaultConcavityMm;
  bool fixed_k = false;  // -k given: a fixed K fit instead of the tolerance
};

// `--pairs`: the pairs `kccd pairs` proves never to come within the margin, or to touch at every
// configuration, join the ignore list (with the SRDF's).
std::string withProvenPairs(const std::string& text, const ImportArgs& args) {
  const Model m = parseModel(text, args.urdf + " (imported)");
  std::vector<modelling::PairReport> reports;
  {
    Progress progress("proving pairs", args.quiet);
    reports =
        modelling::provePairs(m, {.max_boxes = args.max_boxes, .progress = [&](double f) { progress.update(f); }});
  }
  const modelling::IgnorePlan plan =
      modelling::ignoreList(m, reports, {.keep_adjacent = args.keep_adjacent, .world_is_link = true});
  int never = 0, touching = 0, undecided = 0, rigid = 0, adjacent = 0;
  for (const auto& r : reports) {
    rigid += r.rigid;
    adjacent += r.adjacent;
    never += !r.rigid && r.verdict == modelling::Verdict::Never;
    touching += !r.rigid && r.verdict == modelling::Verdict::AlwaysTouching;
    undecided += r.verdict == modelling::Verdict::Undecided;
  }
  if (!args.quiet)
    std::cerr << "pairs: " << rigid << " rigid, " << adjacent << " adjacent" << (args.keep_adjacent ? " (kept)" : "")
              << ", " << never << " never within the margin, " << touching << " always touching, " << undecided
              << " undecided (of " << reports.size() << "); " << plan.ignore.size() << " ignored\n";
  const auto& ignore = plan.ignore;
  std::string out = modelling::withIgnoreList(text, args.urdf + " (imported)", ignore);
  (void)parseModel(out, args.urdf + " (imported)");
  return out;
}

Exit runImport(const ImportArgs& args) {
  modelling::ImportOptions opt;
  opt.srdf = args.srdf;
  opt.fit = {.method = args.hulls     ? modelling::FitMethod::Hull
                       : args.fixed_k ? modelling::FitMethod::Points
                                      : modelling::FitMethod::Tolerance,
             .points = args.points,
             .tolerance = args.tolerance_mm * 1e-3,
             .max_pieces = piecesOption(args.pieces),
             .concavity = args.concavity_mm * 1e-3};
  checkFitOptions(opt.fit);
  opt.safety_margin = args.margin;
  opt.visuals = !args.no_visuals;
  opt.keep_adjacent = args.keep_adjacent;
  for (const std::string& p : args.packages) {
    const std::size_t eq = p.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == p.size())
      throw UsageError("--package-path: expected NAME=DIR, got '" + p + "'");
    opt.packages[p.substr(0, eq)] = p.substr(eq + 1);
  }
  std::string text;
  {
    Progress progress("fitting links", args.quiet);
    opt.progress = [&](double f) { progress.update(f); };
    text = modelling::importUrdf(args.urdf, opt);
  }
  if (args.pairs) text = withProvenPairs(text, args);
  if (args.output.empty() || args.output == "-") {
    std::cout << text;
  } else {
    writeFileAtomically(args.output, text);
    if (!args.quiet) std::cerr << "wrote " << args.output << "\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addImport(CLI::App& app) {
  auto args = std::make_shared<ImportArgs>();
  CLI::App* sub = app.add_subcommand(
      "import",
      "Converts a URDF into a KCCD model: joints and origins mapped, each link's collision geometry (boxes, "
      "cylinders, spheres analytically; meshes in any format Assimp reads: STL, OBJ, DAE, PLY, glTF, ...) fitted with "
      "a conservative SSCH");
  sub->add_option("urdf", args->urdf, "URDF file")->required();
  sub->add_option("--srdf", args->srdf, "SRDF file: its disable_collisions become pairs: ignore");
  CLI::Option* points = sub->add_option(
      "--points,-k", args->points, "Expert knob: exactly K core points per link (1 ... 16), instead of --tolerance");
  CLI::Option* tolerance =
      sub->add_option("--tolerance", args->tolerance_mm,
                      "Millimetres each link's volume may reach outside the link's convex hull: per link the fewest "
                      "points that meet it (the K = 8 fit, else hull vertices added farthest first)")
          ->capture_default_str()
          ->check(finiteIn(1e-6, 1e6))
          ->excludes(points);
  addPieceOptions(*sub, args->pieces, args->concavity_mm,
                  "Concave links (each piece a body LINK/1, LINK/2, ... with link: LINK)");
  sub->add_option("--margin", args->margin, "safety_margin written into the model (metres)")
      ->capture_default_str()
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_option("--package-path", args->packages, "Resolves package://NAME/... meshes: NAME=DIR (repeatable)");
  sub->add_option("-o,--output", args->output, "Model file to write (default: standard output)");
  sub->add_flag(
      "--no-visuals", args->no_visuals,
      "Leave out the links' <visual> geometry (written as visuals: for drawing; their mesh files must exist)");
  sub->add_flag("--pairs", args->pairs,
                "Also prove which pairs never come within the margin inside the joint limits, or always touch, "
                "and ignore them (as kccd pairs --write)");
  sub->add_flag("--hulls", args->hulls,
                "Bodies are the links' (with --pieces, each piece's) convex hulls (every hull vertex, no fit): a tight "
                "but slow reference model "
                "to measure what a fit costs (kccd query on both)")
      ->excludes(points)
      ->excludes(tolerance);
  sub->add_flag(
      "--keep-adjacent", args->keep_adjacent,
      "Check links joined by one moving joint (by default they are ignored, as MoveIt does: reason adjacent)");
  sub->add_option("--max-boxes", args->max_boxes, "With --pairs: boxes per pair before a pair is undecided")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000))
      ->needs("--pairs");
  sub->add_flag("--quiet,-q", args->quiet, "No progress display");
  sub->footer(
      "Joint kinds: fixed, revolute, continuous (revolute without limits), prismatic; a floating joint J becomes "
      "J (translation3d: x, y, z) and J_rotation (rotation3d: a rotation vector); a planar joint J becomes J_x, J_y "
      "(prismatic along the plane) and J_yaw (revolute about its normal). Mimic joints are checked as independent "
      "joints (conservative).\n"
      "Ignored pairs, each with its reason in pairs: ignore: links with only fixed joints between them (rigid: one "
      "constant distance), links joined by one moving joint with no link with geometry between them (adjacent, "
      "MoveIt's rule; --keep-adjacent checks them), the SRDF's disable_collisions (srdf), and with --pairs the pairs "
      "proven never "
      "within the margin (never) or touching at every configuration (always_touching).\n"
      "Exit status: 0 done, 2 bad input.");
  return [args, points] {
    args->fixed_k = points->count() > 0;
    return runImport(*args);
  };
}

}  // namespace kccd::cli
