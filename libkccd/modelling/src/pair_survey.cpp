#include "kccd/modelling/pair_survey.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "kccd/checker.hpp"
#include "kccd/distance.hpp"
#include "kccd/modelling/pair_proof.hpp"

namespace kccd::modelling {

Survey surveyStates(const Model& model, const StateLog& log, const SurveyOptions& options) {
  Survey out;
  out.margin = options.margin >= 0 ? options.margin : model.safety_margin;
  // The surveyed model: the checked pairs, then (on request) the ignored ones, same frames.
  Model m = model;
  const std::size_t checked = m.pairs.size();
  if (options.ignored_pairs)
    for (const IgnoredPair& p : model.ignored) {
      const int a = std::min(p.a, p.b), b = std::max(p.a, p.b);
      bool listed = model.bodies[a].frame == model.bodies[b].frame;
      for (const BodyPair& q : m.pairs) listed = listed || (q.a == a && q.b == b);
      if (!listed) m.pairs.push_back({a, b, m.commonAncestor(m.bodies[a].frame, m.bodies[b].frame)});
    }
  for (std::size_t i = 0; i < m.pairs.size(); ++i) {
    PairSurvey s;
    s.a = m.pairs[i].a, s.b = m.pairs[i].b, s.lca = m.pairs[i].lca, s.checked = i < checked;
    s.min_distance = INFINITY;
    out.pairs.push_back(s);
  }
  // Link pairs: each body pair's link pair, in order of first appearance.
  std::vector<std::size_t> link_of(out.pairs.size());
  for (std::size_t i = 0; i < out.pairs.size(); ++i) {
    const PairSurvey& s = out.pairs[i];
    const std::string& la = model.bodies[s.a].linkName();
    const std::string& lb = model.bodies[s.b].linkName();
    std::size_t k = 0;
    for (; k < out.links.size(); ++k) {
      const std::string& ka = model.bodies[out.links[k].a].linkName();
      const std::string& kb = model.bodies[out.links[k].b].linkName();
      if (out.links[k].checked == s.checked && ((ka == la && kb == lb) || (ka == lb && kb == la))) break;
    }
    if (k == out.links.size()) {
      out.links.push_back(s);
    } else {
      ++out.links[k].body_pairs;
    }
    link_of[i] = k;
  }
  std::vector<double> row_min(out.links.size());
  std::vector<char> row_overlap(out.links.size());
  Checker checker(m);
  const QueryOptions q{.type = QueryType::Distances, .margin = out.margin};
  const std::size_t rows = log.rows();
  for (std::size_t row = 0; row < rows; ++row) {
    if (options.progress && row % 256 == 0) options.progress(static_cast<double>(row) / rows);
    const std::span<const double> state = log.row(row);
    const double t = log.times[row] - options.time_offset;
    const QueryResult& r = checker.query(state, state, q);
    ++out.samples;
    if (r.status != Status::Ok) {
      ++out.unsafe, ++out.samples_within;
      continue;
    }
    bool red = false;
    std::fill(row_min.begin(), row_min.end(), INFINITY);
    std::fill(row_overlap.begin(), row_overlap.end(), 0);
    for (const PairDistance& d : r.pairs) {
      PairSurvey& s = out.pairs[d.pair];
      PairSurvey& l = out.links[link_of[d.pair]];
      if (d.distance < row_min[link_of[d.pair]]) row_min[link_of[d.pair]] = d.distance;
      if (d.distance < l.min_distance) l.min_distance = d.distance, l.min_time = t, l.a = s.a, l.b = s.b;
      if (d.distance < s.min_distance) s.min_distance = d.distance, s.min_time = t;
      if (d.distance > out.margin) continue;
      if (s.within++ == 0) s.first_within = t;
      s.last_within = t;
      red = red || s.checked;
      if (d.distance <= 0.0) {
        ++s.overlapping;
        const Penetration p = penetration(checker.sweptVolume(s.a, s.lca), checker.sweptVolume(s.b, s.lca));
        if (p.overlapping) s.max_penetration = std::max(s.max_penetration, p.depth);
        l.max_penetration = std::max(l.max_penetration, s.max_penetration);
        row_overlap[link_of[d.pair]] = 1;
      }
    }
    for (std::size_t k = 0; k < out.links.size(); ++k) {
      PairSurvey& l = out.links[k];
      l.overlapping += row_overlap[k];
      if (!(row_min[k] <= out.margin)) continue;
      if (l.within++ == 0) l.first_within = t;
      l.last_within = t;
    }
    out.samples_within += red;
  }
  for (std::vector<PairSurvey>* list : {&out.pairs, &out.links})
    for (PairSurvey& s : *list)
      if (!std::isfinite(s.min_distance)) s.min_distance = s.min_time = std::nan("");  // no Ok sample
  if (options.progress) options.progress(1.0);
  return out;
}

StateLog randomStates(const Model& model, int count, std::uint64_t seed) {
  StateLog log;
  log.names = model.stateNames();
  log.circular.assign(model.stateSize(), 0);
  log.logged_velocity.assign(model.stateSize(), 0);
  const auto ranges = jointRanges(model);
  std::mt19937_64 rng(seed);
  for (int i = 0; i < count; ++i) {
    log.times.push_back(i);
    for (const auto& r : ranges)
      log.values.push_back(std::isnan(r[0]) ? 0.0 : std::uniform_real_distribution<double>(r[0], r[1])(rng));
  }
  return log;
}

std::vector<const PairSurvey*> byConcern(const std::vector<PairSurvey>& pairs) {
  std::vector<const PairSurvey*> order;
  for (const PairSurvey& p : pairs) order.push_back(&p);
  std::stable_sort(order.begin(), order.end(), [](const PairSurvey* x, const PairSurvey* y) {
    return x->within != y->within ? x->within > y->within : x->min_distance < y->min_distance;
  });
  return order;
}

}  // namespace kccd::modelling
