// The motion of a synthetic recording (kccd/overlay/synth/synth_trajectory.hpp): the trajectory search,
// the state log and the per-frame check at the logged states.
#include "kccd/overlay/synth/synth_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>

#include "kccd/overlay/synth/synth.hpp"
#include "kccd/safety_status.hpp"

namespace kccd::overlay {

void Trajectory::at(double t, std::span<double> q, std::span<double> qd) const {
  const std::size_t n = centre.size();
  for (std::size_t i = 0; i < n; ++i) {
    const auto& w = waves[i];
    q[i] = centre[i] + w[0] * std::sin(w[1] * t + w[2]) + w[3] * std::sin(w[4] * t + w[5]);
    qd[i] = w[0] * w[1] * std::cos(w[1] * t + w[2]) + w[3] * w[4] * std::cos(w[4] * t + w[5]);
  }
  for (const TrajectoryEvent& e : events) {
    const double x = (t - e.time) / e.half_width;
    if (!(std::abs(x) < 1.0) || e.beta == 0.0) continue;
    // b = beta S(u), S the smootherstep 6u^5 - 15u^4 + 10u^3 of u = (1 - |x|) / (1 - plateau)
    // clamped to 1: position, velocity and acceleration continuous, held at the top.
    const double u = std::min(1.0, (1.0 - std::abs(x)) / (1.0 - e.plateau));
    const double b = e.beta * u * u * u * (u * (6.0 * u - 15.0) + 10.0);
    const double du = u < 1.0 ? -(x > 0 ? 1.0 : -1.0) / ((1.0 - e.plateau) * e.half_width) : 0.0;
    const double db = e.beta * 30.0 * u * u * (u - 1.0) * (u - 1.0) * du;
    for (std::size_t i = 0; i < n; ++i) {
      const double base = q[i], base_d = qd[i];
      q[i] = (1.0 - b) * base + b * e.goal[i];
      qd[i] = (1.0 - b) * base_d + db * (e.goal[i] - base);
    }
  }
}

namespace {

// Position limits of every state value (3-DOF joints do not move: [0, 0]).
struct Limits {
  std::vector<double> lo, hi, amplitude;
};

Limits limitsOf(const Model& m) {
  Limits l;
  for (const Joint& j : m.joints) {
    for (int k = 0; k < j.dof; ++k) {
      double lo = 0, hi = 0, amp = 0;
      if (j.dof == 1) {
        const double free_range = j.type == JointType::Revolute ? M_PI : 0.3;
        lo = j.limits ? (*j.limits)[0] : -free_range;
        hi = j.limits ? (*j.limits)[1] : free_range;
        amp = j.type == JointType::Revolute ? 0.3 : 0.05;
      }
      l.lo.push_back(lo), l.hi.push_back(hi), l.amplitude.push_back(amp);
    }
  }
  return l;
}

}  // namespace

double DistanceProbe::operator()(std::span<const double> q, int* pair) {
  checker_.reset();  // every state on its own: the answer does not depend on the order of queries
  // A state is a box of zero width: its point volumes are the bodies themselves, so the exact
  // stage could only repeat their distances (and the search asks for many thousands of states).
  // Without the pair the closest one is enough (the others are pruned by their bounding spheres);
  // with it, every distance, so that among equal ones the pair is the last, as always.
  const QueryResult& r = checker_.query(q, q,
                                        QueryOptions{.type = pair ? QueryType::Distances : QueryType::NClosest,
                                                     .n = 1,
                                                     .exact_below = -std::numeric_limits<double>::infinity()});
  if (r.status != Status::Ok) return -1.0;
  if (pair) {
    *pair = -1;
    for (const PairDistance& p : r.pairs)
      if (p.distance == r.min_distance) *pair = p.pair;
  }
  return r.min_distance;
}

Trajectory searchTrajectory(const Model& m, const TrajectorySearch& a, double t0, double t1, double dt) {
  const int n = m.stateSize();
  const Limits lim = limitsOf(m);
  const double margin = m.safety_margin;
  const double near_target = margin > 0 ? 0.5 * margin : 0.01;
  std::mt19937_64 rng(a.seed * 0x9E3779B97F4A7C15ull + 1);
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0));
  };
  DistanceProbe probe(m);
  static const bool debug = std::getenv("KCCD_SYNTH_DEBUG") != nullptr;
  std::vector<double> q(n), qd(n);
  const int samples = static_cast<int>(std::ceil((t1 - t0) / dt)) + 1;
  auto minOver = [&](const Trajectory& tr, double from, double to) {
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < samples; ++k) {
      const double t = t0 + k * dt;
      if (t < from || t > to) continue;
      tr.at(t, q, qd);
      best = std::min(best, probe(q));
    }
    return best;
  };
  bool any_pair = !m.pairs.empty();
  if (!any_pair && a.collision)
    throw SynthError(a.model + ": the model checks no body pair, so it cannot collide (use --no-collision)");

  // TrajectoryEvent times: near, collision, near (a near one instead of the collision with --no-collision).
  const double span = a.seconds;
  // Bumps last at least half a second (a robot's pace), so a short recording has fewer of them.
  const double w = std::clamp(0.12 * span, 0.35, 0.9);
  std::vector<TrajectoryEvent> plan;
  // The collision (or the middle near one) first; the others where they fit.
  for (const auto& [f, kind] : {std::pair{0.6, TrajectoryEvent::Collision}, std::pair{0.25, TrajectoryEvent::Near},
                                std::pair{0.87, TrajectoryEvent::Near}}) {
    TrajectoryEvent e;
    e.kind = a.collision ? kind : TrajectoryEvent::Near;
    e.time = f * span;
    e.half_width = w;
    e.plateau = e.kind == TrajectoryEvent::Near ? 0.3 : 0.1;
    bool fits = true;
    for (const TrajectoryEvent& p : plan) fits = fits && std::abs(e.time - p.time) >= 2.0 * w;
    if (fits) plan.push_back(e);
  }
  std::sort(plan.begin(), plan.end(),
            [](const TrajectoryEvent& x, const TrajectoryEvent& y) { return x.time < y.time; });

  for (int attempt = 0; attempt < 40; ++attempt) {
    Trajectory tr;
    tr.centre.assign(n, 0.0);
    tr.waves.assign(n, {});
    for (int i = 0; i < n; ++i) {
      const double mid = 0.5 * (lim.lo[i] + lim.hi[i]);
      double c = (lim.lo[i] <= 0.0 && 0.0 <= lim.hi[i]) ? 0.0 : mid;
      if (attempt > 0) c = std::clamp(c + uniform(-0.3, 0.3) * (lim.hi[i] - lim.lo[i]), lim.lo[i], lim.hi[i]);
      tr.centre[i] = c;
    }
    // The base motion: slow sines, amplitudes shrunk until the motion stays clear of the margin.
    double scale = 1.0;
    for (int i = 0; i < n; ++i)
      tr.waves[i] = {uniform(0.5, 1.0), 2 * M_PI * uniform(0.08, 0.3), uniform(0, 2 * M_PI),
                     uniform(0.2, 0.5), 2 * M_PI * uniform(0.25, 0.6), uniform(0, 2 * M_PI)};
    const std::vector<std::array<double, 6>> unit = tr.waves;
    bool clear = false;
    for (int shrink = 0; shrink < 6 && !clear; ++shrink, scale *= 0.6) {
      for (int i = 0; i < n; ++i) {
        // Room to the limits from the centre.
        const double room = std::max(0.0, std::min(tr.centre[i] - lim.lo[i], lim.hi[i] - tr.centre[i]));
        const double amp = std::min(lim.amplitude[i] * scale, 0.9 * room / 1.5);
        tr.waves[i] = unit[i];
        tr.waves[i][0] *= amp, tr.waves[i][3] *= amp;
      }
      const double d = minOver(tr, t0, t1);
      clear = d > 1.1 * margin + 0.002;
      if (debug) std::fprintf(stderr, "attempt %d scale %.3f base min distance %.4f\n", attempt, scale, d);
    }
    if (!clear) continue;

    // Events: towards a random colliding configuration; near ones stop at about half the margin.
    bool ok = true;
    for (TrajectoryEvent e : plan) {
      bool found = false;
      for (int tries = 0; tries < 300 && !found; ++tries) {
        e.goal.assign(n, 0.0);
        // Within 1.05 rad (0.18 m) of the centre: joint speeds stay those of a robot at work.
        for (int i = 0; i < n; ++i) {
          const double reach = lim.amplitude[i] * 3.5;
          e.goal[i] = std::clamp(tr.centre[i] + uniform(-reach, reach), lim.lo[i], lim.hi[i]);
        }
        if (!(probe(e.goal) <= 0.0)) continue;
        if (e.kind == TrajectoryEvent::Collision) {  // a goal well inside the collision: a contact of some duration
          std::vector<double> part(n);
          for (int i = 0; i < n; ++i) part[i] = tr.centre[i] + 0.8 * (e.goal[i] - tr.centre[i]);
          if (!(probe(part) <= 0.0)) continue;
        }
        Trajectory with = tr;
        int collision_frames = 0;
        const double from = e.time - e.half_width, to = e.time + e.half_width;
        if (e.kind == TrajectoryEvent::Collision) {
          // The smallest blend that collides, then a little more: one short, clear contact.
          double lo = 0.0, hi = 1.0;
          for (int it = 0; it < 18; ++it) {
            e.beta = 0.5 * (lo + hi);
            with.events = tr.events;
            with.events.push_back(e);
            (minOver(with, from, to) <= 0.0 ? hi : lo) = e.beta;
          }
          // Then deeper until the contact lasts about 0.12 to 0.3 s.
          // Frames (at video times) must show it: at least two of them when the window allows.
          const double first = hi;
          for (const double f : {0.15, 0.3, 0.5, 0.75, 1.0}) {
            e.beta = std::min(1.0, first + f * (1.0 - first));
            with.events = tr.events;
            with.events.push_back(e);
            int touching = 0;
            for (int k = 0; k < samples; ++k) {
              const double t = t0 + k * dt;
              if (t < from || t > to) continue;
              with.at(t, q, qd);
              touching += probe(q) <= 0.0;
            }
            collision_frames = 0;
            for (int i = static_cast<int>(std::ceil(from * a.fps)); i / a.fps <= to; ++i) {
              with.at(i / a.fps, q, qd);
              collision_frames += probe(q) <= 0.0;
            }
            if (touching * dt >= std::min(0.12, 0.3 * e.half_width) && collision_frames >= 2) break;
          }
        } else {
          double lo = 0.0, hi = 1.0;
          for (int it = 0; it < 18; ++it) {
            e.beta = 0.5 * (lo + hi);
            with.events = tr.events;
            with.events.push_back(e);
            (minOver(with, from, to) <= near_target ? hi : lo) = e.beta;
          }
          e.beta = lo;
        }
        with.events = tr.events;
        with.events.push_back(e);
        e.min_distance = minOver(with, from, to);
        if (e.kind == TrajectoryEvent::Collision)
          found = e.min_distance <= 0.0 && collision_frames >= 1;
        else
          found = e.min_distance > 0.3 * near_target && e.min_distance <= 1.6 * near_target && e.min_distance <= margin;
      }
      if (debug)
        std::fprintf(stderr, "event %d at %.2f: found %d beta %.3f min %.4f\n", int(e.kind), e.time, int(found), e.beta,
                     e.min_distance);
      if (!found) {
        ok = false;
        break;
      }
      tr.events.push_back(e);
    }
    if (ok) return tr;
  }
  throw SynthError(a.model + ": found no trajectory with near-collisions" +
                   std::string(a.collision ? " and one collision" : "") + " within the joint limits (try another " +
                   spelledField(a.spell, "seed") + " or a longer " + spelledField(a.spell, "seconds") + ")");
}

std::string stateLogText(const Model& m, const Trajectory& tr, double offset, double rate, double duration) {
  const int n = m.stateSize();
  std::string text = "time";
  for (const std::string& name : m.stateNames()) text += "," + name;
  for (const std::string& name : m.stateNames()) text += "," + name + ".vel";
  text += "\n";
  std::vector<double> q(n), qd(n);
  // Log time tau runs from 0 and covers every frame time plus the offset, a few samples beyond.
  const int rows = static_cast<int>(std::ceil((duration + offset) * rate)) + 3;
  char buf[64];
  for (int k = 0; k < rows; ++k) {
    const double tau = k / rate;
    tr.at(tau - offset, q, qd);
    std::snprintf(buf, sizeof buf, "%.6f", tau);
    text += buf;
    for (int i = 0; i < n; ++i) std::snprintf(buf, sizeof buf, ",%.9f", q[i]), text += buf;
    for (int i = 0; i < n; ++i) std::snprintf(buf, sizeof buf, ",%.9f", qd[i]), text += buf;
    text += "\n";
  }
  return text;
}

SynthMotion searchMotion(const Model& m, const TrajectorySearch& search, int frames, double log_rate,
                         double time_offset) {
  const double duration = (frames - 1) / search.fps;
  const double dt = 1.0 / log_rate;
  // The search works on the analytic motion; the frames show the logged one. A trajectory whose
  // frames do not have exactly the wanted collision intervals is searched again (another stream).
  const double max_gap = 1.5 * dt;
  SynthMotion out;
  out.frames = frames;
  out.states.assign(frames, std::vector<double>(m.stateSize()));
  out.min_distance.assign(frames, 0.0);
  out.closest.assign(frames, -1);
  DistanceProbe probe(m);
  for (int round = 0;; ++round) {
    TrajectorySearch ar = search;
    ar.seed = search.seed + 0x51ED270B27ull * static_cast<std::uint64_t>(round);
    out.trajectory = searchTrajectory(m, ar, -time_offset, duration + 0.1, dt);
    out.log_text = stateLogText(m, out.trajectory, time_offset, log_rate, duration);
    out.log = parseStateLog(out.log_text, "states.csv", m);
    // Per frame: the logged state at the frame's log time, its distances.
    for (int i = 0; i < frames; ++i) {
      const double t = i / search.fps;
      if (stateAt(out.log, t + time_offset, max_gap, out.states[i]) == StateMatch::None)
        throw std::logic_error("synth: the log misses frame " + std::to_string(i));
      out.min_distance[i] = probe(out.states[i], &out.closest[i]);
    }
    out.intervals.clear();
    for (int i = 0; i < frames; ++i)
      if (safetyStatus(out.min_distance[i], m.safety_margin) == SafetyStatus::Colliding) {
        if (!out.intervals.empty() && out.intervals.back()[1] == i - 1)
          out.intervals.back()[1] = i;
        else
          out.intervals.push_back({i, i});
      }
    if (out.intervals.size() == (search.collision ? 1u : 0u)) break;
    if (round == 7)
      throw SynthError(search.model + ": the trajectories found have " + std::to_string(out.intervals.size()) +
                       " collision intervals at this frame rate (try another " + spelledField(search.spell, "seed") +
                       ", " + spelledField(search.spell, "fps") + " or " + spelledField(search.spell, "seconds") + ")");
  }
  return out;
}

}  // namespace kccd::overlay
