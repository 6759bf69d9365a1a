// The speed/accuracy trade of the sweep modes and point budgets, measured against a search for
// each pair's closest configuration inside the box.
//
// For each scene and box set (N random braking boxes around configurations clear of the margin),
// the accurate sweep mode at every point budget answers a distances query and a collision
// query per box (cold: table reset; the fastest of --repeats runs). Per pair whose best bound over
// all settings is below kNear, a search inside the box finds a configuration and its distance
// ("found"): an upper bound on the pair's true smallest distance. Two searches run (--oracle both,
// the default): kccd::closestConfiguration (kccd/explain.hpp) and this program's own sampling +
// compass descent (trade_oracle.hpp), kept as a cross-check; found is the smaller of the two (both
// are distances at configurations inside the box), and how often and by how much they differ is
// reported. Every found configuration is re-measured by the exact Checker: its lower bound there
// must not exceed the found distance (else the run fails: the search would be wrong).
// Bodies behind a 3-DOF joint with error bounds (the cell's mock-up pose) are searched over the box
// widened by the error bounds (searchBoxOf), so found distances are ones the true cell can have.
// Then, per setting:
//   distances time, also over the verdict-only distances query (exact stage at the margin) timed
//                 interleaved on the same boxes;
//   looseness in band = found - bound (mm) over every pair whose bound is within kBand of the margin
//                 (whatever was found): p50 / p90 / max, and p90 / max by the number of swept
//                 joints between the two bodies (0-2, 3-5, 6-8, 9-11, 12+);
//   near-pair looseness = found - bound (mm), over pairs found near (found < kNear, found > 0):
//                 median and p90 (leaves out pairs found far whose bound is low);
//   false alarm = a box where some pair's bound <= margin while no found distance is <= margin
//                 (% of all boxes, and of the truly clear ones); per pair: a pair clear of the
//                 margin (found > margin; unsearched pairs count as clear) whose bound is <= margin,
//                 % of all such pairs of all boxes (the CSV column false_alarm_far_pairs counts the
//                 flagged pairs found at kNear or farther: their looseness is not in the statistics);
//   violation   = a bound above found + 1e-9 (must never happen; printed loudly).
// "Truly clear" and "within" are decided by the found distances: a box with a found distance <= the
// margin is certainly within it; a box counted as clear is clear as far as the search can tell
// (a search that misses a closer configuration makes looseness and false alarms look larger).
// Pairs whose best bound is >= kNear are not searched: their true distance is >= kNear, so they
// are never near and never within the margin.
// The point-state row is the exact collision / distances query at the box centre (zero width);
// its looseness column compares its bound with the nominal distance at the centre, which shows
// what the model's joint error bounds (industrial_cell's mock-up pose) cost before any sweeping.
//
// Usage: bench_trade [--n N] [--quick] [--budgets 4,8,...] [--scenes humanoid,industrial_cell]
//                    [--repeats R] [--seed S] [--oracle own|library|both] [--search-effort K]
//                    [--exact default|margin|all|off|METRES] [--splits N] [--split-gap METRES]
//                    [--markdown F] [--csv F] [--plot F.png]
// Exit status: 0 done, 1 error, 2 bad option, 3 a bound violation, 4 a found distance below the
// exact bound at its own configuration (a wrong search).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "kccd/checker.hpp"
#include "kccd/explain.hpp"
#include "kccd/kinematics.hpp"
#include "trade_options.hpp"
#include "trade_oracle.hpp"
#ifdef KCCD_BENCH_WITH_OPENCV
#include "trade_plot.hpp"
#endif

namespace {

using namespace kccd;
using Clock = std::chrono::steady_clock;
constexpr double kDeg = 3.141592653589793 / 180.0;
constexpr double kNear = 0.3;  // m: pairs closer than this count as near
constexpr double kBand = 0.2;  // m above the margin: the pairs whose looseness is reported
// Chain-length bins of the looseness table: swept joints between the two bodies.
constexpr int kChainBins = 5;
constexpr const char* kChainBinNames[kChainBins] = {"0-2", "3-5", "6-8", "9-11", "12+"};
int chainBin(int joints) { return std::min(joints / 3, kChainBins - 1); }
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using bench::Options;
using bench::Oracle;
using bench::parseOptions;

// The measured queries' exact stage (--exact), the same for every setting; kExactAtMargin is
// resolved to the model's margin.
double g_exact_below = -1.0;
int g_splits = QueryOptions{}.exact_splits;           // of the measured queries (--splits)
double g_split_gap = QueryOptions{}.exact_split_gap;  // of the measured queries (--split-gap)
double exactBelow(const Model& m) { return g_exact_below == bench::kExactAtMargin ? m.safety_margin : g_exact_below; }

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "bench_trade: %s\n", message.c_str());
  std::exit(1);
}

// ---------------------------------------------------------------------------------------------
// Boxes

struct BoxSet {
  const char* name;
  double min_deg, max_deg;  // width range of every revolute joint's interval
};
constexpr BoxSet kSets[] = {{"narrow", 1.0, 5.0}, {"wide", 2.0, 20.0}};

struct Box {
  std::vector<double> lower, upper, centre;
};

// A random configuration inside the joint limits and a braking box around it, drawn as
// bench_engine draws its boxes, with the revolute width range of `set` (translation3d 1-5 cm,
// rotation3d up to 2 degrees, prismatic up to 2 cm, as there).
Box randomBox(std::mt19937_64& rng, const Model& m, const BoxSet& set) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Box box;
  box.centre.assign(static_cast<std::size_t>(m.stateSize()), 0.0);
  box.lower = box.upper = box.centre;
  for (const Joint& j : m.joints)
    for (int k = 0; k < j.dof; ++k) {
      const auto s = static_cast<std::size_t>(j.state_offset + k);
      double c = 0.0, width = 0.0;
      if (j.type == JointType::Revolute) {
        const double a = j.limits ? (*j.limits)[0] : -3.0, b = j.limits ? (*j.limits)[1] : 3.0;
        c = a + (b - a) * u(rng);
        width = (set.min_deg + (set.max_deg - set.min_deg) * u(rng)) * kDeg;
      } else if (j.type == JointType::Translation3d) {  // the cable robot's workspace
        const double lo_ws[3] = {1.0, -1.0, 1.2}, hi_ws[3] = {2.2, 1.0, 2.0};
        c = lo_ws[k] + (hi_ws[k] - lo_ws[k]) * u(rng);
        width = 0.01 + 0.04 * u(rng);
      } else if (j.type == JointType::Rotation3d) {
        c = (u(rng) - 0.5) * 2.0;
        width = 2.0 * kDeg * u(rng);
      } else {
        c = 0.1 * u(rng);
        width = 0.02 * u(rng);
      }
      box.centre[s] = c;
      box.lower[s] = c - 0.5 * width;
      box.upper[s] = c + 0.5 * width;
    }
  return box;
}

// `n` boxes whose centre's static clearance (exact distances query) exceeds the margin.
std::vector<Box> drawBoxes(const Model& exact, const BoxSet& set, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Checker statics(exact);
  std::vector<Box> out;
  while (static_cast<int>(out.size()) < n) {
    for (int tries = 0;; ++tries) {
      if (tries > 100000) fail("no configuration clear of the margin found for " + exact.name);
      Box b = randomBox(rng, exact, set);
      statics.reset();
      const QueryResult& r = statics.query(b.centre, b.centre, {.type = QueryType::Distances});
      if (r.status == Status::Ok && r.min_distance > exact.safety_margin) {
        out.push_back(std::move(b));
        break;
      }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Settings and timed queries

// A copy of `base` with every non-fixed joint swept in `mode` and, when budget > 0, that point budget.
std::unique_ptr<Model> variant(const Model& base, SweepMode mode, int budget) {
  auto m = std::make_unique<Model>(base);
  for (Joint& j : m->joints)
    if (j.type != JointType::Fixed) j.sweep = mode;
  if (budget > 0) m->point_budget = budget;
  return m;
}

struct Setting {
  SweepMode mode;
  int budget;
  std::unique_ptr<Model> model;
  std::unique_ptr<Checker> checker;
};

std::vector<Setting> makeSettings(const Model& base, const std::vector<int>& budgets) {
  std::vector<Setting> out;
  for (SweepMode mode : {SweepMode::Accurate})  // the one mode that sweeps (fast is retired: docs/explanation/trade.md)
    for (int budget : budgets) {
      Setting s{mode, budget, variant(base, mode, budget), nullptr};
      s.checker = std::make_unique<Checker>(*s.model);
      out.push_back(std::move(s));
    }
  return out;
}

// The cold time of one query (table reset before each run): the fastest of `repeats` runs, in us.
// `exact_below` as QueryOptions::exact_below.
double coldTime(Checker& checker, const Box& box, bool at_centre, QueryType type, int repeats, double exact_below) {
  const std::vector<double>& lo = at_centre ? box.centre : box.lower;
  const std::vector<double>& hi = at_centre ? box.centre : box.upper;
  double best = kInf;
  for (int r = 0; r < repeats; ++r) {
    checker.reset();
    const auto t0 = Clock::now();
    const QueryResult& res = checker.query(
        lo, hi, {.type = type, .exact_below = exact_below, .exact_splits = g_splits, .exact_split_gap = g_split_gap});
    const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    if (res.status != Status::Ok) fail(std::string("unexpected query status ") + toString(res.status));
    best = std::min(best, us);
  }
  return best;
}

// Every pair's bound of a distances query on `box` (by pair index).
std::vector<double> distancesBounds(Checker& checker, const Box& box, bool at_centre) {
  checker.reset();
  const QueryResult& r = checker.query(at_centre ? box.centre : box.lower, at_centre ? box.centre : box.upper,
                                       {.type = QueryType::Distances,
                                        .exact_below = exactBelow(checker.model()),
                                        .exact_splits = g_splits,
                                        .exact_split_gap = g_split_gap});
  std::vector<double> out(checker.model().pairs.size(), 0.0);
  for (const PairDistance& p : r.pairs) out[static_cast<std::size_t>(p.pair)] = p.distance;
  return out;
}

// ---------------------------------------------------------------------------------------------
// Per box measurements

struct Timing {
  double distances_us = 0.0, collision_us = 0.0;
  double verdict_us = 0.0;  // the distances query refining only verdicts (exact stage at the margin)
};

struct BoxRecord {
  std::vector<Timing> times;                // per setting
  std::vector<std::vector<double>> bounds;  // per setting, per pair
  Timing point;                             // exact query at the centre
  std::vector<double> point_bounds;         // per pair
  std::vector<double> found;                // per pair; +inf when not searched (best bound >= kNear)
  std::vector<double> centre_distance;      // per searched pair: nominal distance at the centre
  bool within = false;                      // some found distance <= margin
};

void measureBox(std::vector<Setting>& settings, Checker& exact, const Box& box, int repeats, BoxRecord& rec) {
  // Settings interleaved per box, so that load on the shared machine hits them alike.
  for (Setting& s : settings) {
    Timing t;
    const double below = exactBelow(*s.model), margin = s.model->safety_margin;
    t.distances_us = coldTime(*s.checker, box, false, QueryType::Distances, repeats, below);
    t.collision_us = coldTime(*s.checker, box, false, QueryType::Collision, repeats, below);
    t.verdict_us = coldTime(*s.checker, box, false, QueryType::Distances, repeats, margin);
    rec.times.push_back(t);
    rec.bounds.push_back(distancesBounds(*s.checker, box, false));
  }
  const double below = exactBelow(exact.model());
  rec.point.distances_us = coldTime(exact, box, true, QueryType::Distances, repeats, below);
  rec.point.collision_us = coldTime(exact, box, true, QueryType::Collision, repeats, below);
  rec.point.verdict_us = rec.point.distances_us;
  rec.point_bounds = distancesBounds(exact, box, true);
}

// Checks of the searches: the two searches against each other (with --oracle both), and every
// found configuration re-measured by the exact Checker (a proven lower bound there, so it must not
// exceed the found distance; without joint error bounds the two should agree).
struct SearchCheck {
  long pairs = 0, own_lower = 0, library_lower = 0;  // lower by more than 0.1 mm than the other
  double max_difference_mm = 0.0;
  long rechecked = 0, exact_above_found = 0;
  double max_found_minus_exact_mm = 0.0;  // over pairs whose bodies have no error bound
};

struct Found {
  double distance = kInf;
  std::vector<double> state;
};

// The closest configuration of one pair inside the box by the chosen search(es): the smaller.
Found closestInBox(const Model& nominal, kccd::bench::BoxSearch& own, const Options& o, int pair, const Box& box,
                   std::uint64_t seed, SearchCheck& check, long& evaluations) {
  Found own_found, library_found;
  if (o.oracle != Oracle::Library) {
    kccd::bench::BoxSearchOptions opt;
    opt.samples *= o.search_effort;
    opt.starts *= o.search_effort;
    opt.max_evaluations *= o.search_effort;
    opt.seed = seed;
    auto r = own.closest(pair, box.lower, box.upper, opt);
    own_found = {r.distance, std::move(r.state)};
    evaluations += r.evaluations;
  }
  if (o.oracle != Oracle::Own) {
    kccd::ClosestConfiguration r = kccd::closestConfiguration(nominal, pair, box.lower, box.upper, {.seed = seed});
    library_found = {r.distance, std::move(r.state)};
    evaluations += r.evaluations;
  }
  if (o.oracle == Oracle::Both) {
    ++check.pairs;
    const double diff = 1000.0 * (own_found.distance - library_found.distance);
    if (diff < -0.1) ++check.own_lower;
    if (diff > 0.1) ++check.library_lower;
    check.max_difference_mm = std::max(check.max_difference_mm, std::abs(diff));
  }
  return own_found.distance <= library_found.distance ? own_found : library_found;
}

// The exact Checker's bound for `pair` at one configuration.
double exactBoundAt(Checker& exact, int pair, const std::vector<double>& state) {
  exact.reset();
  const QueryResult& r = exact.query(state, state, {.type = QueryType::Distances});
  for (const PairDistance& p : r.pairs)
    if (p.pair == pair) return p.distance;
  return kInf;
}

// The box the searches explore: `box`, and for a 3-DOF joint with an error bound e (translation3d:
// metres, rotation3d: radians) each of its values widened by e / sqrt(3), so that the search also
// varies the pose within its error bounds. Every configuration in it is one the error bounds
// allow (a translation within e, and, exp being 1-Lipschitz on SO(3), a rotation within e of one
// in the box), so a distance found in it is a distance the true cell can have.
Box searchBoxOf(const Model& m, const Box& box) {
  Box out = box;
  for (const Joint& j : m.joints) {
    if (!(j.error > 0.0) || j.dof != 3) continue;
    for (int k = 0; k < 3; ++k) {
      const auto s = static_cast<std::size_t>(j.state_offset + k);
      out.lower[s] -= j.error / std::sqrt(3.0);
      out.upper[s] += j.error / std::sqrt(3.0);
    }
  }
  return out;
}

// The projection onto {x : |x - clamp(x, lo, hi)| <= e} (a box widened by a ball of radius e) of
// the three values at x[0..3).
void projectToBoxAndBall(double* x, const double* lo, const double* hi, double e) {
  double c[3], d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    c[k] = std::clamp(x[k], lo[k], hi[k]);
    d2 += (x[k] - c[k]) * (x[k] - c[k]);
  }
  const double d = std::sqrt(d2);
  if (d <= e) return;
  for (int k = 0; k < 3; ++k) x[k] = c[k] + (x[k] - c[k]) * (e / d);
}

// Lowers a found distance of `pair` by varying the 3-DOF joints with an error bound e over their
// whole set of true values: the box widened by a ball of radius e (searchBoxOf() gives the
// searches only the cube inside that ball). A projected descent along the coordinate axes and 26
// fixed directions per joint, steps halving from e. Every configuration it visits is one the
// error bounds allow (translation within e; rotation vectors within e, exp being 1-Lipschitz).
void refineInErrorBall(const Model& nominal, kccd::bench::BoxSearch& own, int pair, const Box& box, Found& f,
                       long& evaluations) {
  std::vector<const Joint*> joints;
  for (const Joint& j : nominal.joints)
    if (j.error > 0.0 && j.dof == 3) joints.push_back(&j);
  if (joints.empty() || f.state.empty()) return;
  std::vector<Vec3> dirs;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c)
        if (a != 0 || b != 0 || c != 0) dirs.push_back(Vec3(a, b, c).normalized());
  std::vector<double> q = f.state, t;
  double best = f.distance;
  for (const Joint* j : joints) {
    const auto s = static_cast<std::size_t>(j->state_offset);
    projectToBoxAndBall(q.data() + s, box.lower.data() + s, box.upper.data() + s, j->error);
  }
  for (double step = 0.5 * joints.front()->error; step > 1e-7; step *= 0.5) {
    bool improved = true;
    for (int round = 0; improved && round < 50; ++round) {
      improved = false;
      for (const Joint* j : joints) {
        const auto s = static_cast<std::size_t>(j->state_offset);
        const double js = step * j->error / joints.front()->error;
        for (const Vec3& d : dirs) {
          t = q;
          for (int k = 0; k < 3; ++k) t[s + static_cast<std::size_t>(k)] += js * d[k];
          projectToBoxAndBall(t.data() + s, box.lower.data() + s, box.upper.data() + s, j->error);
          const double v = own.distanceAt(pair, t);
          ++evaluations;
          if (v < best) {
            best = v;
            q.swap(t);
            improved = true;
          }
        }
      }
    }
  }
  if (best < f.distance) f = {best, std::move(q)};
}

// Searches every pair whose best bound over all settings is below kNear (the others cannot be near).
void searchBox(const Model& nominal, kccd::bench::BoxSearch& own, Checker& exact, const Options& o, const Box& given,
               std::uint64_t seed, BoxRecord& rec, SearchCheck& check, long& evaluations) {
  const Box box = searchBoxOf(nominal, given);
  const std::size_t pairs = nominal.pairs.size();
  rec.found.assign(pairs, kInf);
  rec.centre_distance.assign(pairs, kInf);
  for (std::size_t p = 0; p < pairs; ++p) {
    double best_bound = kInf;
    for (const auto& b : rec.bounds) best_bound = std::min(best_bound, b[p]);
    if (best_bound >= kNear) continue;
    const int pair = static_cast<int>(p);
    Found f = closestInBox(nominal, own, o, pair, box, seed * 1000003 + p, check, evaluations);
    const BodyPair& bp = nominal.pairs[p];
    const bool uncertain = hasErrorBound(nominal, nominal.bodies[static_cast<std::size_t>(bp.a)].frame) ||
                           hasErrorBound(nominal, nominal.bodies[static_cast<std::size_t>(bp.b)].frame);
    if (uncertain) refineInErrorBall(nominal, own, pair, given, f, evaluations);
    rec.found[p] = f.distance;
    rec.centre_distance[p] = own.distanceAt(pair, given.centre);
    if (f.distance <= nominal.safety_margin) rec.within = true;

    const double at_found = exactBoundAt(exact, pair, f.state);
    ++check.rechecked;
    if (at_found > f.distance + 1e-9) ++check.exact_above_found;
    if (!uncertain)
      check.max_found_minus_exact_mm = std::max(check.max_found_minus_exact_mm, 1000.0 * (f.distance - at_found));
  }
}

// ---------------------------------------------------------------------------------------------
// Statistics

// Nearest-rank quantile of `v` (sorted here); NaN when empty.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

struct Row {
  std::string mode;
  int budget = 0;
  double distances_us = kNaN, distances_clear_us = kNaN, distances_within_us = kNaN;  // medians
  double clear_med = kNaN, clear_p90 = kNaN, within_med = kNaN, within_p90 = kNaN;
  double ratio = kNaN;  // collision on truly clear boxes / point-state collision on the same boxes
  double loose_med = kNaN, loose_p90 = kNaN;  // near pairs (found < kNear)
  // Pairs whose bound is within kBand of the margin: overall, and per chain-length bin.
  double band_med = kNaN, band_p90 = kNaN, band_max = kNaN;
  long band_pairs = 0;
  double bin_p90[kChainBins] = {kNaN, kNaN, kNaN, kNaN, kNaN}, bin_max[kChainBins] = {kNaN, kNaN, kNaN, kNaN, kNaN};
  long bin_pairs[kChainBins] = {0, 0, 0, 0, 0};
  double verdict_us = kNaN;    // median verdict-only distances query
  double over_verdict = kNaN;  // median distances / median verdict-only distances
  double alarm_boxes_pct = kNaN, alarm_clear_pct = kNaN, alarm_pairs_pct = kNaN;
  long far_alarms = 0;  // pairs with found >= kNear (not near) whose bound is within the margin
  long violations = 0;
};

struct Violation {
  int box, setting, pair;
  double bound, found;
};

struct SetSummary {
  std::string scene, set;
  int boxes = 0, clear = 0, within = 0;
  long near_pairs = 0;
  std::vector<Row> rows;  // per setting, then the point-state row
  std::vector<Violation> violations;
  SearchCheck check;
  long evaluations = 0;
  double seconds_queries = 0.0, seconds_search = 0.0;
};

// Statistics of one setting's bounds and times over all boxes (`point`: the point-state query).
Row summarise(const std::vector<BoxRecord>& recs, double margin, const std::vector<int>& chain_joints, int setting,
              bool point, std::vector<Violation>& violations) {
  std::vector<double> dist_us, dist_clear_us, dist_within_us, clear_us, within_us, point_clear_us, loose, verdict_us;
  std::vector<double> band, bins[kChainBins];
  long alarms = 0, clear_boxes = 0, pair_alarms = 0, clear_pairs = 0;
  Row row;
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const BoxRecord& r = recs[i];
    const Timing& t = point ? r.point : r.times[static_cast<std::size_t>(setting)];
    const std::vector<double>& bounds = point ? r.point_bounds : r.bounds[static_cast<std::size_t>(setting)];
    const std::vector<double>& truth = point ? r.centre_distance : r.found;
    dist_us.push_back(t.distances_us);
    verdict_us.push_back(t.verdict_us);
    (r.within ? dist_within_us : dist_clear_us).push_back(t.distances_us);
    (r.within ? within_us : clear_us).push_back(t.collision_us);
    if (!r.within) point_clear_us.push_back(r.point.collision_us);
    bool alarm = false;
    for (std::size_t p = 0; p < bounds.size(); ++p) {
      alarm = alarm || bounds[p] <= margin;
      if (!point && truth[p] > margin) {  // truly clear (never searched: found >= kNear, bound too)
        ++clear_pairs;
        pair_alarms += bounds[p] <= margin ? 1 : 0;
        if (truth[p] >= kNear && bounds[p] <= margin) ++row.far_alarms;
      }
      if (!std::isfinite(truth[p])) continue;  // never searched: bound >= kNear in every setting
      if (bounds[p] > truth[p] + 1e-9) {
        ++row.violations;
        violations.push_back({static_cast<int>(i), point ? -1 : setting, static_cast<int>(p), bounds[p], truth[p]});
      }
      if (truth[p] < kNear && truth[p] > 0.0) loose.push_back(1000.0 * (truth[p] - bounds[p]));
      if (bounds[p] <= margin + kBand) {  // every pair the bound puts within the band, whatever was found
        const double l = 1000.0 * (truth[p] - bounds[p]);
        band.push_back(l);
        bins[chainBin(chain_joints[p])].push_back(l);
      }
    }
    if (!r.within) {
      ++clear_boxes;
      alarms += alarm ? 1 : 0;
    }
  }
  row.distances_us = quantile(dist_us, 0.5);
  row.distances_clear_us = quantile(dist_clear_us, 0.5);
  row.distances_within_us = quantile(dist_within_us, 0.5);
  row.clear_med = quantile(clear_us, 0.5);
  row.clear_p90 = quantile(clear_us, 0.9);
  row.within_med = quantile(within_us, 0.5);
  row.within_p90 = quantile(within_us, 0.9);
  row.ratio = row.clear_med / quantile(point_clear_us, 0.5);
  row.loose_med = quantile(loose, 0.5);
  row.loose_p90 = quantile(loose, 0.9);
  row.band_med = quantile(band, 0.5);
  row.band_p90 = quantile(band, 0.9);
  row.band_max = quantile(band, 1.0);
  row.band_pairs = static_cast<long>(band.size());
  for (int b = 0; b < kChainBins; ++b) {
    row.bin_p90[b] = quantile(bins[b], 0.9);
    row.bin_max[b] = quantile(bins[b], 1.0);
    row.bin_pairs[b] = static_cast<long>(bins[b].size());
  }
  row.verdict_us = quantile(verdict_us, 0.5);
  row.over_verdict = row.distances_us / row.verdict_us;
  if (!point) {
    row.alarm_boxes_pct = 100.0 * static_cast<double>(alarms) / static_cast<double>(recs.size());
    if (clear_boxes > 0) row.alarm_clear_pct = 100.0 * static_cast<double>(alarms) / static_cast<double>(clear_boxes);
    if (clear_pairs > 0)
      row.alarm_pairs_pct = 100.0 * static_cast<double>(pair_alarms) / static_cast<double>(clear_pairs);
  }
  return row;
}

// Per pair, the swept (non-fixed) joints between its two bodies: from each body's frame up to,
// not including, their least common ancestor.
std::vector<int> chainJoints(const Model& m) {
  std::vector<int> out;
  for (const BodyPair& p : m.pairs) {
    int n = 0;
    for (const int body : {p.a, p.b})
      for (int f = m.bodies[static_cast<std::size_t>(body)].frame; f != p.lca && f != kWorld;
           f = m.joints[static_cast<std::size_t>(f)].parent)
        n += m.joints[static_cast<std::size_t>(f)].type != JointType::Fixed ? 1 : 0;
    out.push_back(n);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// One scene and box set

SetSummary runSet(const std::string& scene, const BoxSet& set, int set_index, const Options& o) {
  const Model base = loadModel(std::string(KCCD_DATA_DIR) + "/" + scene + ".yaml");
  const auto exact_model = variant(base, SweepMode::Exact, 0);
  Checker exact(*exact_model);
  std::vector<Setting> settings = makeSettings(base, o.budgets);
  std::uint64_t seed = o.seed * 1000003 + static_cast<std::uint64_t>(set_index);
  for (char c : scene) seed = seed * 31 + static_cast<unsigned char>(c);  // the same boxes on every platform
  const std::vector<Box> boxes = drawBoxes(*exact_model, set, o.boxes, seed);

  SetSummary sum;
  sum.scene = scene;
  sum.set = set.name;
  sum.boxes = static_cast<int>(boxes.size());
  std::vector<BoxRecord> recs(boxes.size());
  const auto t0 = Clock::now();
  for (std::size_t i = 0; i < boxes.size(); ++i) measureBox(settings, exact, boxes[i], o.repeats, recs[i]);
  const auto t1 = Clock::now();
  kccd::bench::BoxSearch own(base);
  for (std::size_t i = 0; i < boxes.size(); ++i)
    searchBox(base, own, exact, o, boxes[i], seed + i, recs[i], sum.check, sum.evaluations);
  sum.seconds_queries = std::chrono::duration<double>(t1 - t0).count();
  sum.seconds_search = std::chrono::duration<double>(Clock::now() - t1).count();

  for (const BoxRecord& r : recs) {
    (r.within ? sum.within : sum.clear) += 1;
    for (double f : r.found) sum.near_pairs += f < kNear ? 1 : 0;
  }
  const std::vector<int> chain_joints = chainJoints(base);
  for (std::size_t s = 0; s < settings.size(); ++s) {
    Row row = summarise(recs, base.safety_margin, chain_joints, static_cast<int>(s), false, sum.violations);
    row.mode = toString(settings[s].mode);
    row.budget = settings[s].budget;
    sum.rows.push_back(row);
  }
  Row point = summarise(recs, base.safety_margin, chain_joints, -1, true, sum.violations);
  point.mode = "point state (centre)";
  point.budget = base.point_budget;
  sum.rows.push_back(point);
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Output

std::string num(double v, const char* fmt = "%.1f") {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// A CSV field: empty when there is no value.
std::string csvNum(double v, const char* fmt) { return std::isfinite(v) ? num(v, fmt) : std::string(); }

std::string setTitle(const SetSummary& s) {
  for (const BoxSet& b : kSets)
    if (s.set == b.name)
      return s.scene + ", " + b.name + " boxes (revolute widths " + num(b.min_deg, "%g") + "-" + num(b.max_deg, "%g") +
             " deg)";
  return s.scene + ", " + s.set;
}

std::string markdownTable(const SetSummary& s, double margin) {
  std::ostringstream md;
  md << "### " << setTitle(s) << "\n\n"
     << s.boxes << " boxes: " << s.clear << " truly clear, " << s.within << " within the margin (" << margin << " m); "
     << s.near_pairs << " near pair-boxes (found < " << kNear << " m). Search: " << s.check.rechecked
     << " found configurations re-measured by the exact Checker, its bound above the found distance "
     << s.check.exact_above_found << " times, found - exact bound at most "
     << num(s.check.max_found_minus_exact_mm, "%.6f") << " mm (pairs without joint error bounds)";
  if (s.check.pairs > 0)
    md << "; own search vs kccd::closestConfiguration over " << s.check.pairs << " pairs: own lower by > 0.1 mm "
       << s.check.own_lower << " times, library lower " << s.check.library_lower << " times, largest difference "
       << num(s.check.max_difference_mm, "%.3f") << " mm";
  md << ".\n\n"
     << "| mode | budget | distances µs | / verdict-only | collision µs clear (med / p90) | collision µs within (med / "
        "p90) "
        "| clear / point state | looseness mm in band (p50 / p90 / max) | near-pair looseness mm (med / p90) "
        "| false alarms % boxes (of clear) | false alarms % pairs | flagged pairs found >= 0.3 m |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : s.rows) {
    const bool point = r.mode.rfind("point", 0) == 0;
    md << "| " << r.mode << " | " << r.budget << " | " << num(r.distances_us) << " | "
       << (point ? std::string("-") : num(r.over_verdict, "%.2f")) << " | " << num(r.clear_med) << " / "
       << num(r.clear_p90) << " | " << num(r.within_med) << " / " << num(r.within_p90) << " | " << num(r.ratio, "%.2f")
       << " | " << num(r.band_med) << " / " << num(r.band_p90) << " / " << num(r.band_max) << " | " << num(r.loose_med)
       << " / " << num(r.loose_p90) << " | " << num(r.alarm_boxes_pct) << " (" << num(r.alarm_clear_pct) << ") | "
       << num(r.alarm_pairs_pct, "%.2f") << " | " << (point ? std::string("-") : std::to_string(r.far_alarms))
       << " |\n";
  }
  md << "\nLooseness in band by swept joints between the two bodies, p90 / max mm (pair-boxes):\n\n| mode | budget |";
  for (const char* b : kChainBinNames) md << " " << b << " |";
  md << "\n|---|---|";
  for (int b = 0; b < kChainBins; ++b) md << "---|";
  md << "\n";
  for (const Row& r : s.rows) {
    if (r.mode.rfind("point", 0) == 0) continue;
    md << "| " << r.mode << " | " << r.budget << " |";
    for (int b = 0; b < kChainBins; ++b)
      md << " "
         << (r.bin_pairs[b] > 0
                 ? num(r.bin_p90[b]) + " / " + num(r.bin_max[b]) + " (" + std::to_string(r.bin_pairs[b]) + ")"
                 : std::string("-"))
         << " |";
    md << "\n";
  }
  md << "\n";
  return md.str();
}

std::string exactName(double below) {
  if (below == kInf) return "every pair (--exact all)";
  if (below == -kInf) return "off (--exact off)";
  if (below == bench::kExactAtMargin) return "pairs within the margin (--exact margin)";
  if (below < 0.0)
    return "the library's default: collision queries pairs within the margin, distance queries pairs within " +
           num(kBand, "%g") + " m of it (QueryOptions::exact_band)";
  return "pairs within " + num(below, "%g") + " m (--exact " + num(below, "%g") + ")";
}

std::string markdownNotes(const Options& o) {
  std::ostringstream md;
  md << "Exact stage: " << exactName(o.exact_below) << "; box splitting (QueryOptions::exact_splits): "
     << (o.splits > 1 ? "up to " + std::to_string(o.splits) + " sub-boxes per pair, split gap " +
                            num(o.split_gap * 1e3, "%g") + " mm"
                      : std::string("off"))
     << ". \"/ verdict-only\": the median distances query over the median distances query whose exact stage "
        "refines only the pairs within the margin (the verdicts), measured interleaved on the same boxes. "
        "Looseness in band: found distance minus bound over every pair whose bound is within "
     << num(kBand, "%g")
     << " m of the margin (found by the searches; whatever it is), overall and by the number "
        "of swept joints between the two bodies. For bodies behind a joint with error bounds (the cell's mock-up "
        "pose) the searches also vary the pose within them, so a found distance is one the cell can have. Cold queries "
        "(table reset before each; the same box repeated, so CPU caches are warm), the fastest of "
     << o.repeats
     << " runs per box, median / p90 over the boxes (nearest rank). "
        "\"clear\"/\"within\": boxes whose closest found configuration is beyond / within the margin. "
        "\"clear / point state\": median collision query on the truly clear boxes over the median exact "
        "collision query at the same boxes' centres. Near-pair looseness: found distance minus bound over pairs "
        "found near (found < 0.3 m, not touching; leaves out pairs found far whose bound is low); for the point-state "
        "row, the nominal distance at the centre minus "
        "the exact bound there (the cost of joint error bounds). False alarms: boxes where some bound is "
        "within the margin but no found distance is, as % of all boxes (and of the truly clear ones); "
        "pairs: % of all checked pairs (of all boxes) that are clear of the margin and flagged within it "
        "(flagged pairs found 0.3 m or farther, left out of the looseness: CSV false_alarm_far_pairs).\n\n";
  return md.str();
}

std::string csvText(const std::vector<SetSummary>& sets) {
  std::ostringstream c;
  c << "scene,set,mode,budget,boxes,clear_boxes,within_boxes,near_pairs,distances_us_median,"
       "distances_clear_us_median,distances_within_us_median,"
       "collision_clear_us_median,collision_clear_us_p90,collision_within_us_median,collision_within_us_p90,"
       "clear_over_point_state,looseness_mm_median,looseness_mm_p90,false_alarm_boxes_pct,"
       "false_alarm_clear_boxes_pct,false_alarm_pairs_pct,false_alarm_far_pairs,violations,"
       "verdict_only_distances_us_median,distances_over_verdict_only,band_pairs,band_looseness_mm_p50,"
       "band_looseness_mm_p90,band_looseness_mm_max";
  for (const char* b : kChainBinNames)
    c << ",band_p90_mm_joints_" << b << ",band_max_mm_joints_" << b << ",band_pairs_joints_" << b;
  c << "\n";
  for (const SetSummary& s : sets)
    for (const Row& r : s.rows) {
      c << s.scene << "," << s.set << "," << (r.mode.rfind("point", 0) == 0 ? "point_state" : r.mode) << "," << r.budget
        << "," << s.boxes << "," << s.clear << "," << s.within << "," << s.near_pairs << ","
        << csvNum(r.distances_us, "%.3f") << "," << csvNum(r.distances_clear_us, "%.3f") << ","
        << csvNum(r.distances_within_us, "%.3f") << "," << csvNum(r.clear_med, "%.3f") << ","
        << csvNum(r.clear_p90, "%.3f") << "," << csvNum(r.within_med, "%.3f") << "," << csvNum(r.within_p90, "%.3f")
        << "," << csvNum(r.ratio, "%.4f") << "," << csvNum(r.loose_med, "%.4f") << "," << csvNum(r.loose_p90, "%.4f")
        << "," << csvNum(r.alarm_boxes_pct, "%.2f") << "," << csvNum(r.alarm_clear_pct, "%.2f") << ","
        << csvNum(r.alarm_pairs_pct, "%.2f") << ","
        << (r.mode.rfind("point", 0) == 0 ? std::string() : std::to_string(r.far_alarms)) << "," << r.violations << ","
        << csvNum(r.verdict_us, "%.3f") << "," << csvNum(r.over_verdict, "%.4f") << "," << r.band_pairs << ","
        << csvNum(r.band_med, "%.4f") << "," << csvNum(r.band_p90, "%.4f") << "," << csvNum(r.band_max, "%.4f");
      for (int b = 0; b < kChainBins; ++b)
        c << "," << csvNum(r.bin_p90[b], "%.4f") << "," << csvNum(r.bin_max[b], "%.4f") << "," << r.bin_pairs[b];
      c << "\n";
    }
  return c.str();
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.close();
  if (!f) {
    std::fprintf(stderr, "bench_trade: could not write %s\n", path.c_str());
    std::exit(1);
  }
}

void reportViolations(const SetSummary& s, const Model& m) {
  if (s.violations.empty()) return;
  std::fprintf(stderr,
               "\n!!!!!!!! %zu BOUND VIOLATIONS in %s: a bound above a distance found inside the box !!!!!!!!\n",
               s.violations.size(), setTitle(s).c_str());
  for (std::size_t i = 0; i < std::min<std::size_t>(20, s.violations.size()); ++i) {
    const Violation& v = s.violations[i];
    const BodyPair& p = m.pairs[static_cast<std::size_t>(v.pair)];
    std::fprintf(stderr, "  box %d setting %s pair %s-%s: bound %.9f m > found %.9f m\n", v.box,
                 v.setting < 0 ? "point state" : s.rows[static_cast<std::size_t>(v.setting)].mode.c_str(),
                 m.bodies[static_cast<std::size_t>(p.a)].name.c_str(),
                 m.bodies[static_cast<std::size_t>(p.b)].name.c_str(), v.bound, v.found);
  }
}

#ifdef KCCD_BENCH_WITH_OPENCV
void writePlot(const std::string& path, const std::vector<SetSummary>& sets, int columns) {
  std::vector<kccd::bench::TradeCell> cells;
  for (const SetSummary& s : sets) {
    kccd::bench::TradeCell cell{setTitle(s) + ", " + std::to_string(s.boxes) + " boxes", {}};
    for (const Row& r : s.rows) {
      if (r.mode.rfind("point", 0) == 0) continue;
      if (cell.series.empty() || cell.series.back().label != r.mode) cell.series.push_back({r.mode, {}});
      cell.series.back().points.push_back({r.budget, r.distances_us, r.band_p90, r.alarm_boxes_pct});
    }
    cells.push_back(std::move(cell));
  }
  std::string error;
  if (!kccd::bench::writeTradePlot(path, "KCCD point budgets (accurate sweeps): speed vs looseness and false alarms",
                                   cells, columns, error)) {
    std::fprintf(stderr, "bench_trade: %s\n", error.c_str());
    std::exit(1);
  }
}
#endif

const char* oracleName(Oracle o) {
  return o == Oracle::Own       ? "own box search"
         : o == Oracle::Library ? "kccd::closestConfiguration"
                                : "both (the smaller)";
}

}  // namespace

int main(int argc, char** argv) try {
  const Options o = parseOptions(argc, argv);
  g_exact_below = o.exact_below;
  g_splits = o.splits;
  g_split_gap = o.split_gap;
  const auto start = Clock::now();
  std::vector<SetSummary> sets;
  std::string md = "## Speed / accuracy trade (bench_trade)\n\n" + markdownNotes(o);
  std::cout << md << std::flush;
  long violations = 0, search_faults = 0;
  for (const std::string& scene : o.scenes) {
    const Model m = loadModel(std::string(KCCD_DATA_DIR) + "/" + scene + ".yaml");
    for (int k = 0; k < 2; ++k) {
      SetSummary s = runSet(scene, kSets[k], k, o);
      std::fprintf(stderr, "bench_trade: %s: queries %.1f s, search %.1f s (%ld distance evaluations, %s)\n",
                   setTitle(s).c_str(), s.seconds_queries, s.seconds_search, s.evaluations, oracleName(o.oracle));
      if (o.oracle == Oracle::Both)
        std::fprintf(stderr,
                     "bench_trade:   searches compared over %ld pairs: own lower by > 0.1 mm %ld times, "
                     "library lower %ld times, largest difference %.3f mm\n",
                     s.check.pairs, s.check.own_lower, s.check.library_lower, s.check.max_difference_mm);
      std::fprintf(stderr,
                   "bench_trade:   found configurations re-measured by the exact Checker: %ld, its bound above the "
                   "found distance %ld times; found - exact bound at most %.6f mm (pairs without error bounds)\n",
                   s.check.rechecked, s.check.exact_above_found, s.check.max_found_minus_exact_mm);
      search_faults += s.check.exact_above_found;
      reportViolations(s, m);
      for (const Row& r : s.rows) violations += r.violations;
      const std::string table = markdownTable(s, m.safety_margin);
      std::cout << table << std::flush;
      md += table;
      sets.push_back(std::move(s));
    }
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const std::string footer = "Search: " + std::string(oracleName(o.oracle)) +
                             ". Violations (bound above a found "
                             "distance): " +
                             std::to_string(violations) + ". Run time " + num(seconds) + " s.\n";
  std::cout << footer;
  md += footer;
  if (!o.markdown.empty()) writeFile(o.markdown, md);
  if (!o.csv.empty()) writeFile(o.csv, csvText(sets));
#ifdef KCCD_BENCH_WITH_OPENCV
  if (!o.plot.empty()) writePlot(o.plot, sets, 2);
#endif
  if (search_faults > 0)
    std::fprintf(stderr,
                 "\n!!!!!!!! bench_trade: %ld found distances below the exact bound at their own configuration: "
                 "the search is wrong, the looseness figures are not trustworthy !!!!!!!!\n",
                 search_faults);
  if (violations > 0) {
    std::fprintf(stderr, "\n!!!!!!!! bench_trade: %ld BOUND VIOLATIONS (see above) !!!!!!!!\n", violations);
    return 3;
  }
  return search_faults > 0 ? 4 : 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_trade: %s\n", e.what());
  return 1;
}
