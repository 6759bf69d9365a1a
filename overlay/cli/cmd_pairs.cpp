// `kccd pairs MODEL`: proves which pairs can never come within the margin over the joint limits,
// which are rigid or adjacent, and (with --states) surveys how close each pair comes in a recording.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "cli_progress.hpp"
#include "commands.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/pair_survey.hpp"
#include "kccd/modelling/yaml_edit.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

struct PairsArgs {
  std::string model, states, ignore_columns;
  double margin = -1.0, time_offset = 0.0;
  int max_boxes = 2000, random = 0;
  std::uint64_t seed = 1;
  bool write = false, json = false, quiet = false, all = false, keep_adjacent = false, ignored = false;
};

// The proofs hold for the model as it was read: the list is written only into that same text.
void writeIgnoreList(const std::string& model, const std::string& proven_text,
                     const std::vector<modelling::IgnoreEntry>& ignore) {
  editFile(
      model, [&](const std::string& text) { return modelling::withIgnoreList(text, model, ignore); }, &proven_text);
}

std::string pairName(const Model& m, int a, int b) { return m.bodies[a].name + " - " + m.bodies[b].name; }

Exit runSurvey(const PairsArgs& args, const Model& m) {
  const bool random = args.random > 0;
  const StateLog log = random ? modelling::randomStates(m, args.random, args.seed)
                              : loadStateLog(args.states, m, splitCommas(args.ignore_columns));
  const std::string source = random ? "random states inside the joint limits (seed " + std::to_string(args.seed) + ")"
                                    : "recorded states from " + args.states;
  const std::string when = random ? "sample" : "at (s)";
  modelling::Survey s;
  {
    Progress progress("surveying " + std::to_string(log.rows()) + " states", args.quiet || args.json);
    s = modelling::surveyStates(m, log,
                                {.margin = args.margin,
                                 .time_offset = args.time_offset,
                                 .ignored_pairs = args.ignored,
                                 .progress = [&](double f) { progress.update(f); }});
  }
  const std::vector<const modelling::PairSurvey*> order = modelling::byConcern(s.pairs);
  // Reported by link: the pieces of a concave link are one link (its closest pieces named).
  const std::vector<const modelling::PairSurvey*> link_order = modelling::byConcern(s.links);
  const double n = static_cast<double>(std::max<std::size_t>(1, s.samples));
  if (args.json) {
    nlohmann::json j{{"margin", s.margin},
                     {"states", random ? nlohmann::json("random") : nlohmann::json(args.states)},
                     {"time_offset", args.time_offset},
                     {"samples", s.samples},
                     {"samples_within", s.samples_within},
                     {"unsafe", s.unsafe},
                     {"pairs", nlohmann::json::array()}};
    for (const auto* p : order) {
      nlohmann::json o{{"a", m.bodies[p->a].name},
                       {"b", m.bodies[p->b].name},
                       {"frame", m.frameName(p->lca)},
                       {"checked", p->checked},
                       {"within", p->within},
                       {"fraction", p->within / n},
                       {"overlapping", p->overlapping},
                       {"min_distance", number(p->min_distance)},
                       {"min_time", number(p->min_time)}};
      if (!p->checked) o["ignored"] = modelling::currentIgnoreReason(m, p->a, p->b);
      if (p->within > 0) o["first_within"] = p->first_within, o["last_within"] = p->last_within;
      if (p->overlapping > 0) o["max_penetration"] = p->max_penetration;
      j["pairs"].push_back(o);
    }
    j["links"] = nlohmann::json::array();
    for (const auto* p : link_order) {
      nlohmann::json o{{"a", m.bodies[p->a].linkName()},
                       {"b", m.bodies[p->b].linkName()},
                       {"closest_bodies", {m.bodies[p->a].name, m.bodies[p->b].name}},
                       {"body_pairs", p->body_pairs},
                       {"checked", p->checked},
                       {"within", p->within},
                       {"fraction", p->within / n},
                       {"overlapping", p->overlapping},
                       {"min_distance", number(p->min_distance)},
                       {"min_time", number(p->min_time)}};
      if (p->within > 0) o["first_within"] = p->first_within, o["last_within"] = p->last_within;
      j["links"].push_back(o);
    }
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  std::cout << "model " << m.name << ": " << s.samples << " " << source << ", margin " << s.margin << " m\n"
            << s.samples_within << " states (" << formatNumber(100.0 * s.samples_within / n, 3)
            << " %) have a checked pair within the margin"
            << (s.unsafe ? ", " + std::to_string(s.unsafe) + " unsafe" : "") << "\n";
  std::cout << std::left << std::setw(44) << "  pair" << std::setw(16) << "within margin" << std::setw(14)
            << "closest (m)" << std::setw(12) << when << "note\n";
  int quiet_pairs = 0;
  for (const auto* p : link_order) {
    if (p->within == 0 && !args.all) {
      ++quiet_pairs;
      continue;
    }
    const double f = p->within / n;
    std::string note = p->within == 0 ? ""
                       : f >= 0.95    ? "always or nearly: adjacent, or a fit too loose?"
                       : f >= 0.5     ? "often"
                                      : "sometimes";
    if (p->overlapping)
      note += (note.empty() ? "" : "; ") + std::string("volumes overlap in ") + std::to_string(p->overlapping) +
              " states, up to " + formatNumber(p->max_penetration, 3) + " m";
    if (p->within > 0 && !random)
      note += "; " + formatNumber(p->first_within, 6) + " ... " + formatNumber(p->last_within, 6) + " s";
    if (!p->checked) note = "(ignored: " + modelling::currentIgnoreReason(m, p->a, p->b) + ") " + note;
    if (p->body_pairs > 1)
      note += (note.empty() ? "" : "; ") + std::string("closest pieces ") + pairName(m, p->a, p->b) + " of " +
              std::to_string(p->body_pairs) + " piece pairs";
    std::cout << "  " << std::left << std::setw(42) << (m.bodies[p->a].linkName() + " - " + m.bodies[p->b].linkName())
              << std::setw(16) << (std::to_string(p->within) + " (" + formatNumber(100.0 * f, 3) + " %)")
              << std::setw(14) << (std::isnan(p->min_distance) ? std::string("-") : formatNumber(p->min_distance, 4))
              << std::setw(12) << (std::isnan(p->min_time) ? std::string("-") : formatNumber(p->min_time, 6)) << note
              << "\n";
  }
  if (quiet_pairs > 0) std::cout << quiet_pairs << " pairs never within the margin (--all lists them)\n";
  std::cout << "A survey is evidence, not a proof: nothing is ignored from it. A pair within the margin in a run "
               "that touched nothing: refit its bodies (kccd fit -k), or ignore it by hand after checking.\n";
  return Exit::Ok;
}

Exit runPairs(const PairsArgs& args) {
  std::string model_text;
  const Model m = loadOrExplain(args.model, &model_text);
  const bool survey = !args.states.empty() || args.random > 0;
  if (args.ignored && !survey) throw UsageError("--ignored: needs --states or --random");
  if (survey) return runSurvey(args, m);
  std::vector<modelling::PairReport> reports;
  {
    Progress progress("proving pairs", args.quiet || args.json);
    reports = modelling::provePairs(
        m, {.margin = args.margin, .max_boxes = args.max_boxes, .progress = [&](double f) { progress.update(f); }});
  }
  const double margin = args.margin >= 0 ? args.margin : m.safety_margin;
  const modelling::IgnorePlan plan = modelling::ignoreList(m, reports, {.keep_adjacent = args.keep_adjacent});

  if (args.json) {
    nlohmann::json j;
    j["margin"] = margin;
    j["pairs"] = nlohmann::json::array();
    for (const auto& r : reports) {
      nlohmann::json o{{"a", m.bodies[r.a].name},        {"b", m.bodies[r.b].name}, {"frame", m.frameName(r.lca)},
                       {"verdict", toString(r.verdict)}, {"adjacent", r.adjacent},  {"rigid", r.rigid},
                       {"checked", r.checked},           {"boxes", r.boxes}};
      if (!r.checked) o["ignored"] = modelling::currentIgnoreReason(m, r.a, r.b);
      if (const std::string why = modelling::plannedIgnoreReason(plan, m, r.a, r.b); !why.empty())
        o["ignore_reason"] = why;
      if (r.verdict == modelling::Verdict::Never || r.rigid) o["bound"] = number(r.bound);
      if (r.verdict == modelling::Verdict::Meets) {
        o["witness_state"] = r.witness;
        o["witness_distance"] = r.witness_distance;
      }
      j["pairs"].push_back(o);
    }
    j["ignore"] = nlohmann::json::array();
    for (const auto& e : plan.ignore) j["ignore"].push_back({e.a, e.b, toString(e.reason)});
    j["dropped"] = nlohmann::json::array();
    for (const auto& e : plan.dropped) j["dropped"].push_back({e.a, e.b, toString(e.reason)});
    if (args.write) j["written"] = args.model;
    if (args.write) writeIgnoreList(args.model, model_text, plan.ignore);
    std::cout << j.dump(2) << "\n";
    return Exit::Ok;
  }
  const modelling::VerdictCounts counts = modelling::countVerdicts(reports);
  std::cout << "model " << m.name << ": " << reports.size() << " body pairs in different frames, margin " << margin
            << " m, over the joint limits\n";
  std::cout << std::left << std::setw(44) << "  pair" << std::setw(17) << "verdict" << std::setw(12) << "bound (m)"
            << "note\n";
  for (const auto& r : reports) {
    const std::string why = modelling::plannedIgnoreReason(plan, m, r.a, r.b);
    // Pairs that meet and stay checked are the normal case: listed with --all only.
    if (r.verdict == modelling::Verdict::Meets && why.empty() && !args.all) continue;
    std::string note = modelling::verdictNote(r);
    if (!r.rigid && r.adjacent && why == "adjacent")
      note += "; adjacent (one moving joint): ignored as MoveIt does";
    else if (!r.rigid && r.adjacent && args.keep_adjacent)
      note += "; adjacent, kept (--keep-adjacent)";
    if (!r.checked) note += " (ignored now: " + modelling::currentIgnoreReason(m, r.a, r.b) + ")";
    std::cout << "  " << std::left << std::setw(42) << pairName(m, r.a, r.b) << std::setw(17)
              << (r.rigid ? std::string("rigid") : std::string(toString(r.verdict))) << std::setw(12)
              << (r.verdict == modelling::Verdict::Never || r.rigid ? formatNumber(r.bound, 4) : std::string("-"))
              << note << "\n";
  }
  std::cout << counts.rigid << " rigid, " << counts.adjacent << " adjacent" << (args.keep_adjacent ? " (kept)" : "")
            << "; " << counts.never << " never, " << counts.always_touching << " always touching, " << counts.meets
            << " meet, " << counts.undecided << " undecided, " << counts.unbounded << " unbounded"
            << (args.all ? "" : " (pairs that meet: --all lists them)") << "\n";
  for (const auto& e : plan.dropped)
    std::cout << "no longer ignored: " << e.a << " - " << e.b << " (was " << toString(e.reason)
              << ", which no longer holds)\n";
  if (args.write) {
    writeIgnoreList(args.model, model_text, plan.ignore);
    std::cout << "wrote " << plan.ignore.size() << " pairs to pairs: ignore in " << args.model << "\n";
  } else {
    std::cout << "suggested:\npairs:\n  ignore: " << modelling::flowPairs(plan.ignore, 11) << "\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addPairs(CLI::App& app) {
  auto args = std::make_shared<PairsArgs>();
  CLI::App* sub = app.add_subcommand(
      "pairs",
      "Proves which body pairs can never come within the safety margin anywhere inside the joint limits (the "
      "engine's conservative sweeps, split until proven), finds rigid and adjacent pairs and adjacent pairs that "
      "always touch; with --states, surveys how often each pair comes within the margin in a recording");
  sub->add_option("model", args->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--margin", args->margin, "Safety margin in metres (default: the model's)")
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_option("--max-boxes", args->max_boxes, "Box budget per pair before giving up (undecided)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000000));
  sub->add_flag("--write", args->write,
                "Write the ignore list (rigid, proven, always touching, adjacent, and the file's own entries) into "
                "the model, in place, each entry with its reason");
  sub->add_flag("--keep-adjacent", args->keep_adjacent,
                "Check pairs joined by one moving joint (by default they are ignored, as MoveIt does)");
  auto* states = sub->add_option("--states", args->states,
                                 "Survey a state log (CSV) instead of proving: per checked pair, how many recorded "
                                 "states come within the margin, how close, when (nothing is written)");
  auto* random = sub->add_option("--random", args->random,
                                 "Survey N configurations drawn inside the joint limits instead of proving (MoveIt's "
                                 "'often in collision' sampling; reported, nothing is written)")
                     ->check(CLI::Range(1, 100000000))
                     ->excludes(states);
  sub->add_option("--seed", args->seed, "With --random: the seed of the draw")->capture_default_str()->needs(random);
  sub->add_option("--time-offset", args->time_offset,
                  "With --states: seconds added to the video time to get the log time (as kccd overlay); times are "
                  "reported as video times")
      ->check(finiteIn(-1e9, 1e9))
      ->needs(states);
  sub->add_option("--ignore-columns", args->ignore_columns, "With --states: comma-separated log columns to skip")
      ->needs(states);
  sub->add_flag("--ignored", args->ignored, "With --states or --random: also survey the pairs the model ignores");
  sub->add_flag("--all", args->all, "Also list the pairs that meet (with --states: the pairs never within the margin)");
  sub->add_flag("--json", args->json, "Machine-readable output");
  sub->add_flag("--quiet,-q", args->quiet, "No progress display");
  sub->footer(
      "Rigid: only fixed joints between the two bodies, one constant distance, decided exactly (always within the "
      "margin or never) and ignored. Adjacent: one moving joint between them and no body on a link in between (links "
      "without geometry merged, as MoveIt's rule); ignored by --write unless --keep-adjacent (such links overlap at "
      "their joint by construction). Bodies in the world frame are obstacles for this rule (kccd import's adjacent "
      "entries for a URDF's root link stay).\n"
      "Limits: revolute joints without limits are proven over a full turn, rotation3d over all orientations; "
      "prismatic joints without limits and translation3d are unbounded (never proven).\n"
      "A proof holds while the joints stay inside their limits. Ignore entries whose reason no longer holds "
      "(a failed proof, a joint no longer fixed) are dropped by --write and listed.\n"
      "Exit status: 0 done, 2 bad input.");
  for (const char* proof_only : {"--write", "--keep-adjacent", "--max-boxes"}) {  // not for a survey
    states->excludes(sub->get_option(proof_only));
    random->excludes(sub->get_option(proof_only));
  }
  return [args] { return runPairs(*args); };
}

}  // namespace kccd::cli
