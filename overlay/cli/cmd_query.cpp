// `kccd query MODEL --lower .. --upper ..`: one conservative query over an interval box.
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>

#include "cli_args.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/checker.hpp"
#include "kccd/explain.hpp"

namespace kccd::cli {
namespace {

struct QueryArgs {
  std::string model;
  std::string lower, upper, state;
  std::string type = "collision";
  int n = 1;
  double margin = -1.0;
  double budget_us = 0.0;
  std::string exact = "band";
  double exact_band = 0.2;
  int exact_splits = QueryOptions{}.exact_splits;
  double exact_split_gap = QueryOptions{}.exact_split_gap;
  bool json = false;
  bool explain = false;
};

// --exact: which pairs the exact stage refines (QueryOptions::exact_below); `margin` is the
// query's margin (the model's unless --margin).
double parseExact(const std::string& e, double margin) {
  if (const std::optional<double> word = exactBelowFromWord(e, margin)) return *word;
  try {
    std::size_t used = 0;
    const double d = std::stod(e, &used);
    if (used == e.size() && std::isfinite(d) && d >= 0.0 && d <= kMaxModelLength) return d;
  } catch (const std::exception&) {
  }
  throw UsageError("--exact: expected band, margin, all, off or a distance from 0 to 1e6 m, got '" + printable(e) +
                   "'");
}

QueryType parseType(const std::string& t) {
  if (const std::optional<QueryType> type = queryTypeFromString(t)) return *type;
  throw UsageError("--type: unknown query type '" + t + "' (collision, closest, nclosest, distances)");
}

// The configuration as {state name: value}.
nlohmann::json stateObject(const Model& m, const std::vector<double>& state) {
  nlohmann::json o = nlohmann::json::object();
  for (std::size_t i = 0; i < state.size(); ++i) o[m.stateNames()[i]] = state[i];
  return o;
}

nlohmann::json explainJson(const Model& m, const std::vector<PairExplanation>& explained) {
  nlohmann::json out = nlohmann::json::array();
  for (const PairExplanation& e : explained) {
    const BodyPair& p = m.pairs[static_cast<std::size_t>(e.pair)];
    out.push_back({{"a", m.bodies[static_cast<std::size_t>(p.a)].name},
                   {"b", m.bodies[static_cast<std::size_t>(p.b)].name},
                   {"bound", number(e.bound)},
                   {"distance", number(e.closest.distance)},
                   {"verdict", toString(e.verdict)},
                   {"state", stateObject(m, e.closest.state)},
                   {"point_a", vec3(e.closest.point_a)},
                   {"point_b", vec3(e.closest.point_b)},
                   {"evaluations", e.closest.evaluations}});
  }
  return out;
}

void printExplain(const Model& m, const std::vector<PairExplanation>& explained, double margin) {
  std::cout << "explain: " << explained.size() << " flagged pair" << (explained.size() == 1 ? "" : "s")
            << " (bound <= margin " << margin << " m); closest configuration found by local search\n";
  for (const PairExplanation& e : explained) {
    const BodyPair& p = m.pairs[static_cast<std::size_t>(e.pair)];
    std::cout << "  " << m.bodies[static_cast<std::size_t>(p.a)].name << " - "
              << m.bodies[static_cast<std::size_t>(p.b)].name << ": bound " << e.bound << " m, found "
              << e.closest.distance << " m: " << toString(e.verdict) << "\n    at";
    for (std::size_t i = 0; i < e.closest.state.size(); ++i)
      std::cout << (i == 0 ? " " : ", ") << m.stateNames()[i] << " = " << formatNumber(e.closest.state[i], 10);
    std::cout << "\n";
  }
}

Exit runQuery(const QueryArgs& args) {
  const Model m = loadOrExplain(args.model);
  const QueryType type = parseType(args.type);
  const StateBox box =
      parseStateBox(m, args.state, args.lower, args.upper,
                    "the interval box needs --lower and --upper (or --state for a single configuration)", false);
  const std::vector<double>& lower = box.lower;
  const std::vector<double>& upper = box.upper;
  Checker checker(m);
  QueryOptions opt;
  opt.type = type;
  opt.n = args.n;
  opt.margin = args.margin;
  opt.budget_us = args.budget_us;
  opt.exact_below = parseExact(args.exact, args.margin >= 0.0 ? args.margin : m.safety_margin);
  opt.exact_band = args.exact_band;
  opt.exact_splits = args.exact_splits;
  opt.exact_split_gap = args.exact_split_gap;
  const QueryResult& r = checker.query(lower, upper, opt);
  const bool explain = args.explain && r.status == Status::Ok;
  const std::vector<PairExplanation> explained =
      explain ? explainFlagged(m, lower, upper, args.margin) : std::vector<PairExplanation>{};

  if (args.json) {
    nlohmann::json j;
    j["type"] = toString(r.type);
    j["status"] = toString(r.status);
    j["collision"] = r.collision;
    j["min_distance"] = number(r.min_distance);
    j["margin"] = r.margin;
    j["pairs"] = nlohmann::json::array();
    for (const PairDistance& pd : r.pairs) {
      const BodyPair& p = m.pairs[pd.pair];
      nlohmann::json o{{"a", m.bodies[p.a].name},
                       {"b", m.bodies[p.b].name},
                       {"frame", m.frameName(p.lca)},
                       {"distance", pd.distance},
                       {"fresh", pd.fresh}};
      if (pd.has_witness) {
        o["witness_a"] = vec3(pd.witness_a);
        o["witness_b"] = vec3(pd.witness_b);
      }
      j["pairs"].push_back(o);
    }
    j["stats"] = {{"time_us", r.stats.time_us},
                  {"pairs_checked", r.stats.pairs_checked},
                  {"gjk_calls", r.stats.gjk_calls},
                  {"gjk_iterations", r.stats.gjk_iterations},
                  {"exact_calls", r.stats.exact_calls},
                  {"split_pairs", r.stats.split_pairs},
                  {"volumes_swept", r.stats.volumes_swept},
                  {"budget_exhausted", r.stats.budget_exhausted}};
    if (explain) j["explain"] = explainJson(m, explained);
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "status " << toString(r.status) << ": "
              << (r.collision ? "COLLISION (some pair within the margin, or unsafe status)" : "clear") << "\n"
              << "min distance " << r.min_distance << " m (lower bound over the whole box), margin " << r.margin
              << " m\n";
    for (const PairDistance& pd : r.pairs) {
      const BodyPair& p = m.pairs[pd.pair];
      std::cout << "  " << std::left << std::setw(40) << (m.bodies[p.a].name + " - " + m.bodies[p.b].name)
                << std::setw(14) << pd.distance << "[" << m.frameName(p.lca) << "]"
                << (pd.fresh ? "" : " (carried over)") << "\n";
    }
    std::cout << "time " << r.stats.time_us << " us, " << r.stats.pairs_checked << " pairs checked, "
              << r.stats.gjk_calls << " GJK calls (" << r.stats.gjk_iterations << " iterations), "
              << r.stats.exact_calls << " exact-stage calls, " << r.stats.split_pairs << " pairs split"
              << (r.stats.budget_exhausted ? ", budget exhausted" : "") << "\n";
    if (explain) printExplain(m, explained, r.margin);
  }
  if (r.status != Status::Ok) {
    std::cerr << "kccd: query status " << toString(r.status) << " (unsafe)\n";
    return Exit::Unsafe;
  }
  return Exit::Ok;
}

}  // namespace

Runner addQuery(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* sub = app.add_subcommand("query",
                                     "One query over an interval box: every distance is a lower bound over all "
                                     "configurations with lower <= q <= upper");
  sub->add_option("model", args->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("--lower", args->lower, "Lower interval ends, comma-separated, in state order (see kccd info)");
  sub->add_option("--upper", args->upper, "Upper interval ends, comma-separated, in state order");
  sub->add_option("--state", args->state, "A single configuration (zero-width interval)");
  sub->add_option("--type", args->type, "collision | closest | distances | nclosest (cheapest first)")
      ->capture_default_str();
  sub->add_option("--n", args->n, "Number of pairs for --type nclosest")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--margin", args->margin, "Safety margin in metres (default: the model's)")
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_option("--budget-us", args->budget_us, "Time budget in microseconds (default: unlimited)")
      ->check(finiteIn(0.0, kMaxBudgetUs));
  sub->add_option("--exact", args->exact,
                  "Which pairs the exact stage refines (swept volumes with no point budget, tight, slower): "
                  "band (collision: every pair whose bound is within the margin, which decides every verdict; "
                  "closest, nclosest, distances: also every pair within --exact-band above it, for tight distances), "
                  "margin (only the verdicts), all (every pair), off (point volumes only), or a distance in metres")
      ->capture_default_str();
  sub->add_option("--exact-band", args->exact_band,
                  "With --exact band: how far above the margin (metres) a distance query's pairs are refined")
      ->capture_default_str()
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_option("--exact-splits", args->exact_splits,
                  "Distance queries: a pair in the band, moved by some accurate joint, whose bound lies more than "
                  "--exact-split-gap below its distance at a configuration of the box has its box split into up to "
                  "this many sub-boxes (a power of two), each refined by the exact stage; 0 or 1: never")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxExactSplits));
  sub->add_option("--exact-split-gap", args->exact_split_gap,
                  "Metres: how far a pair's bound may lie below its distance at a configuration of the box before "
                  "the box is split (the looseness accepted before paying for splits; smaller is tighter and slower)")
      ->capture_default_str()
      ->check(finiteIn(0.0, kMaxModelLength));
  sub->add_flag("--json", args->json, "Machine-readable output");
  sub->add_flag("--explain", args->explain,
                "For every pair whose bound is <= the margin, search the box for its closest configuration and "
                "print it with a verdict: 'real' (that configuration is within the margin: a proven collision) or "
                "'possible' (none found within it; a local search, not a proof of safety). JSON: an \"explain\" "
                "array of {a, b, bound, distance, verdict, state, point_a, point_b}");
  sub->footer("Exit status: 0 answered (collision or not), 2 bad input, 3 unsafe query status.");
  return [args] { return runQuery(*args); };
}

}  // namespace kccd::cli
