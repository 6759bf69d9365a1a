// `kccd pairs MODEL`: proves which pairs can never come within the margin over the joint limits.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::cli {
namespace {

struct PairsArgs {
  std::string model;
  double margin = -1.0;
  int max_boxes = 2000;
  bool write = false, json = false, quiet = false, all = false;
};

// The proofs hold for the model as it was read: the list is written only into that same text.
void writeIgnoreList(const std::string& model, const std::string& proven_text,
                     const std::vector<std::array<std::string, 2>>& ignore) {
  editFile(model, [&](const std::string& text) { return modelling::withIgnoreList(text, model, ignore); },
           &proven_text);
}

Exit runPairs(const PairsArgs& args) {
  std::string model_text;
  const Model m = loadOrExplain(args.model, &model_text);
  std::vector<modelling::PairReport> reports;
  {
    Progress progress("proving pairs", args.quiet || args.json);
    reports = modelling::provePairs(
        m, {.margin = args.margin, .max_boxes = args.max_boxes, .progress = [&](double f) { progress.update(f); }});
  }
  const double margin = args.margin >= 0 ? args.margin : m.safety_margin;
  const std::vector<std::array<std::string, 2>> ignore = modelling::ignoreList(m, reports);

  if (args.json) {
    nlohmann::json j;
    j["margin"] = margin;
    j["pairs"] = nlohmann::json::array();
    for (const auto& r : reports) {
      nlohmann::json o{{"a", m.bodies[r.a].name}, {"b", m.bodies[r.b].name}, {"frame", m.frameName(r.lca)},
                       {"verdict", toString(r.verdict)}, {"adjacent", r.adjacent}, {"checked", r.checked},
                       {"boxes", r.boxes}};
      if (r.verdict == modelling::Verdict::Never) o["bound"] = number(r.bound);
      if (r.verdict == modelling::Verdict::Meets) {
        o["witness_state"] = r.witness;
        o["witness_distance"] = r.witness_distance;
      }
      j["pairs"].push_back(o);
    }
    j["ignore"] = ignore;
    if (args.write) j["written"] = args.model;
    if (args.write) writeIgnoreList(args.model, model_text, ignore);
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  int counts[5] = {0, 0, 0, 0, 0};
  for (const auto& r : reports) ++counts[static_cast<int>(r.verdict)];
  std::cout << "model " << m.name << ": " << reports.size() << " body pairs in different frames, margin " << margin
            << " m, over the joint limits\n";
  std::cout << std::left << std::setw(44) << "  pair" << std::setw(17) << "verdict" << std::setw(12) << "bound (m)"
            << "note\n";
  for (const auto& r : reports) {
    const bool interesting = r.verdict != modelling::Verdict::Meets || args.all;
    if (!interesting) continue;
    std::string note;
    switch (r.verdict) {
      case modelling::Verdict::Never: note = "proven in " + std::to_string(r.boxes) + " boxes: safe to ignore"; break;
      case modelling::Verdict::AlwaysTouching: note = "adjacent, touch at every configuration: ignore"; break;
      case modelling::Verdict::Meets: note = "within the margin at a state inside the limits"; break;
      case modelling::Verdict::Undecided: note = "no proof within " + std::to_string(r.boxes) + " boxes: keep"; break;
      case modelling::Verdict::Unbounded: note = "a joint without limits moves them: keep"; break;
    }
    if (!r.checked) note += " (ignored now)";
    std::cout << "  " << std::left << std::setw(42) << (m.bodies[r.a].name + " - " + m.bodies[r.b].name)
              << std::setw(17) << toString(r.verdict) << std::setw(12)
              << (r.verdict == modelling::Verdict::Never ? format(r.bound, 4) : std::string("-")) << note << "\n";
  }
  std::cout << counts[0] << " never, " << counts[1] << " always touching, " << counts[2] << " meet, " << counts[3]
            << " undecided, " << counts[4] << " unbounded" << (args.all ? "" : " (pairs that meet: --all lists them)")
            << "\n";
  if (args.write) {
    writeIgnoreList(args.model, model_text, ignore);
    std::cout << "wrote " << ignore.size() << " pairs to pairs: ignore in " << args.model << "\n";
  } else {
    std::cout << "suggested:\npairs:\n  ignore: " << modelling::flowPairs(ignore, 11) << "\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addPairs(CLI::App& app) {
  auto args = std::make_shared<PairsArgs>();
  CLI::App* sub = app.add_subcommand(
      "pairs",
      "Proves which body pairs can never come within the safety margin anywhere inside the joint limits (the "
      "engine's conservative sweeps, split until proven), and finds adjacent pairs that always touch");
  sub->add_option("model", args->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--margin", args->margin, "Safety margin in metres (default: the model's)")
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_option("--max-boxes", args->max_boxes, "Box budget per pair before giving up (undecided)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000000));
  sub->add_flag("--write", args->write,
                "Write the ignore list (proven + always touching + already ignored) into the model, in place");
  sub->add_flag("--all", args->all, "Also list the pairs that meet");
  sub->add_flag("--json", args->json, "Machine-readable output");
  sub->add_flag("--quiet,-q", args->quiet, "No progress display");
  sub->footer(
      "Limits: revolute joints without limits are proven over a full turn, rotation3d over all orientations; "
      "prismatic joints without limits and translation3d are unbounded (never proven).\n"
      "A proof holds while the joints stay inside their limits. Exit status: 0 done, 2 bad input.");
  return [args] { return runPairs(*args); };
}

}  // namespace kccd::cli
