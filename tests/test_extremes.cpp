// Conservativeness at the numerical extremes a model file and a query can hold: revolute angles
// up to 1e300 and limits of +-3.4e38, axes with components from 1e-150 to 1e200 (not normalised
// in the file), coordinates and radii near the loader's 1e6 m bound, rotation vectors up to 1e300,
// prismatic and translation values up to 3.4e38 - for every joint type and every query type.
//
// Models are written as YAML text and loaded with the real loader, so the file's meaning is what
// is checked. The oracle shares no code with libkccd: it reads the raw numbers it wrote, does its
// kinematics in long double (cosl/sinl, its own Rodrigues and rpy), relative to the pair's common
// ancestor frame, and measures with the independent minimum-norm-point distance.
//
// KCCD_SOAK=N multiplies the case count by N / 50000 (as the other property tests); KCCD_SEED=S
// reruns one case.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>

#include "kccd/checker.hpp"
#ifdef KCCD_WITH_MODELLING
#include "kccd/modelling/pair_proof.hpp"
#endif
#include "support/random_shapes.hpp"
#include "support/reference_distance.hpp"

namespace kccd {
namespace {

using Real = long double;
using V3 = Eigen::Matrix<Real, 3, 1>;
using M3 = Eigen::Matrix<Real, 3, 3>;

long envOr(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atol(v) : fallback;
}

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
int uniformInt(std::mt19937_64& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
bool chance(std::mt19937_64& rng, double p) { return uniform(rng, 0.0, 1.0) < p; }
double signedPow10(std::mt19937_64& rng, double e_lo, double e_hi) {
  return (chance(rng, 0.5) ? -1.0 : 1.0) * std::pow(10.0, uniform(rng, e_lo, e_hi));
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// --- The oracle's own kinematics, in long double. ---
M3 rodrigues(const V3& axis_unit, Real angle) {
  M3 k;
  k << 0, -axis_unit.z(), axis_unit.y(), axis_unit.z(), 0, -axis_unit.x(), -axis_unit.y(), axis_unit.x(), 0;
  return M3::Identity() * cosl(angle) + sinl(angle) * k + (1 - cosl(angle)) * axis_unit * axis_unit.transpose();
}
M3 rotationVector(const V3& w) {
  // |w| without overflow for components up to 1e300 (long double holds their squares).
  const Real angle = w.norm();
  if (angle == 0) return M3::Identity();
  return rodrigues(w / angle, angle);
}
M3 rpy(Real r, Real p, Real y) {
  return rodrigues(V3::UnitZ(), y) * rodrigues(V3::UnitY(), p) * rodrigues(V3::UnitX(), r);
}

// What the generator wrote, kept to feed the oracle.
struct RawJoint {
  int parent = kWorld;
  JointType type = JointType::Fixed;
  double xyz[3] = {0, 0, 0}, rpy[3] = {0, 0, 0}, axis[3] = {0, 0, 1};
  double error = 0.0;
  int offset = 0, dof = 0;
  bool has_limits = false;
  double limits[2] = {0, 0};
};
struct RawBody {
  int frame = kWorld;
  std::vector<Eigen::Vector3d> points;
  double radius = 0.0;
};
struct RawModel {
  std::vector<RawJoint> joints;
  std::vector<RawBody> bodies;
  double margin = 0.0;
  std::string yaml;
};

RawModel generate(std::mt19937_64& rng) {
  RawModel raw;
  std::ostringstream y;
  raw.margin = chance(rng, 0.2) ? 0.0 : uniform(rng, 0.0, 0.05);
  const int budgets[] = {4, 8, 32};
  y << "kccd: 1\nsafety_margin: " << num(raw.margin) << "\npoint_budget: " << budgets[uniformInt(rng, 0, 2)]
    << "\njoints:\n";
  const int nj = uniformInt(rng, 1, 5);
  int offset = 0;
  const char* modes[] = {"exact", "fast", "fast", "accurate", "accurate"};
  for (int i = 0; i < nj; ++i) {
    RawJoint j;
    j.parent = uniformInt(rng, -1, i - 1);
    const int t = uniformInt(rng, 0, 9);
    j.type = t < 5   ? JointType::Revolute
             : t < 7 ? JointType::Prismatic
             : t < 8 ? JointType::Fixed
             : t < 9 ? JointType::Translation3d
                     : JointType::Rotation3d;
    const double reach = chance(rng, 0.1) ? 9.9e5 : 0.4;  // origins near the loader's bound, sometimes
    for (double& v : j.xyz) v = uniform(rng, -reach, reach);
    for (double& v : j.rpy) v = chance(rng, 0.15) ? signedPow10(rng, 0, 300) : uniform(rng, -3.2, 3.2);
    // Axes as files write them: any scale, per component or overall, sometimes axis-aligned.
    const Eigen::Vector3d d = testing::randomUnit(rng);
    const int style = uniformInt(rng, 0, 3);
    const double overall = std::pow(10.0, uniform(rng, -150, 200));
    for (int k = 0; k < 3; ++k) {
      j.axis[k] = style == 0 ? d[k] : style == 1 ? d[k] * overall : signedPow10(rng, -150, 200);
      if (style == 3 && k != 0 && chance(rng, 0.5)) j.axis[k] = 0.0;
    }
    y << "  - {name: j" << i
      << ", parent: " << (j.parent == kWorld ? std::string("world") : "j" + std::to_string(j.parent))
      << ", type: " << toString(j.type) << ", origin: {xyz: [" << num(j.xyz[0]) << ", " << num(j.xyz[1]) << ", "
      << num(j.xyz[2]) << "], rpy: [" << num(j.rpy[0]) << ", " << num(j.rpy[1]) << ", " << num(j.rpy[2]) << "]}";
    if (j.type == JointType::Revolute || j.type == JointType::Prismatic) {
      y << ", axis: [" << num(j.axis[0]) << ", " << num(j.axis[1]) << ", " << num(j.axis[2]) << "]";
      // Limits as files write them: "unlimited", beyond a turn, narrow but far out, ordinary.
      const int kind = uniformInt(rng, 0, 6);
      const double far_out = signedPow10(rng, 3, 300);
      const double choices[][2] = {{-3.4e38, 3.4e38}, {-2e16, 2e16}, {far_out, far_out + 0.3}, {-0.3, 1.2}, {-3, 3}};
      if (kind < 5) {
        j.has_limits = true;
        j.limits[0] = choices[kind][0];
        j.limits[1] = std::max(choices[kind][0], choices[kind][1]);
        if (j.type == JointType::Prismatic && kind >= 2) j.limits[0] *= 0.1, j.limits[1] *= 0.1;
        y << ", limits: [" << num(j.limits[0]) << ", " << num(j.limits[1]) << "]";
      }
    }
    if (j.type != JointType::Fixed) y << ", sweep: " << modes[uniformInt(rng, 0, 4)];
    if (j.type == JointType::Translation3d && chance(rng, 0.7))
      j.error = chance(rng, 0.1) ? 9e5 : uniform(rng, 0, 0.05);
    if (j.type == JointType::Rotation3d && chance(rng, 0.7))
      j.error = chance(rng, 0.1) ? uniform(rng, 3, 1e3) : uniform(rng, 0, 0.4);
    if (j.error > 0.0) y << ", error: " << num(j.error);
    y << "}\n";
    j.dof = j.type == JointType::Fixed ? 0 : (j.type == JointType::Revolute || j.type == JointType::Prismatic) ? 1 : 3;
    j.offset = offset;
    offset += j.dof;
    raw.joints.push_back(j);
  }
  y << "bodies:\n";
  const int nb = uniformInt(rng, 2, 4);
  for (int i = 0; i < nb; ++i) {
    RawBody b;
    b.frame = uniformInt(rng, -1, nj - 1);
    const double far = chance(rng, 0.1) ? 9.9e5 : 0.6;
    const Eigen::Vector3d centre(uniform(rng, -far, far), uniform(rng, -far, far), uniform(rng, -far, far));
    const double size = chance(rng, 0.1) ? std::pow(10.0, uniform(rng, -6, 5)) : uniform(rng, 0.01, 0.3);
    b.points = testing::randomCloud(rng, uniformInt(rng, 1, 6), centre, size);
    for (auto& p : b.points)
      for (int k = 0; k < 3; ++k) p[k] = std::clamp(p[k], -1e6, 1e6);
    b.radius = chance(rng, 0.2) ? 0.0 : chance(rng, 0.05) ? uniform(rng, 0, 1e6) : uniform(rng, 0.0, 0.05);
    y << "  - {name: b" << i
      << ", frame: " << (b.frame == kWorld ? std::string("world") : "j" + std::to_string(b.frame))
      << ", radius: " << num(b.radius) << ", points: [";
    for (std::size_t k = 0; k < b.points.size(); ++k)
      y << (k ? ", " : "") << "[" << num(b.points[k].x()) << ", " << num(b.points[k].y()) << ", "
        << num(b.points[k].z()) << "]";
    y << "]}\n";
    raw.bodies.push_back(b);
  }
  raw.yaml = y.str();
  return raw;
}

// An interval per state value, reaching the extremes a query can be given.
void extremeBox(std::mt19937_64& rng, const Model& m, std::vector<double>& lower, std::vector<double>& upper) {
  const double widths[] = {0.0, 1e-12, 1e-6, 0.02, 0.35, 1.0, 3.3, 6.3, 7.0, 1e3, 1e20};
  lower.assign(m.stateSize(), 0.0);
  upper.assign(m.stateSize(), 0.0);
  for (const Joint& j : m.joints) {
    const bool angular = j.type == JointType::Revolute || j.type == JointType::Rotation3d;
    for (int k = 0; k < j.dof; ++k) {
      const int s = j.state_offset + k;
      const double pick = uniform(rng, 0, 1);
      double centre = angular ? uniform(rng, -3.5, 3.5) : uniform(rng, -0.35, 0.35);
      if (angular && pick < 0.35) centre = signedPow10(rng, 3, 300);
      if (!angular && pick < 0.05) centre = signedPow10(rng, 3, 38.5);
      double width = widths[uniformInt(rng, 0, 10)] * (angular ? 1.0 : 0.1);
      if (j.sweep == SweepMode::Exact) width = 0.0;
      if (j.sweep != SweepMode::Exact && angular && pick > 0.95) {  // "unlimited" as exporters write it
        lower[s] = -3.4e38;
        upper[s] = 3.4e38;
        continue;
      }
      lower[s] = centre;
      upper[s] = centre + width;
      if (upper[s] < lower[s] || !std::isfinite(upper[s])) upper[s] = lower[s];
    }
  }
}

// One configuration of the box (corners, edges, inside) and a realisation of the error bounds.
struct Sample {
  std::vector<double> q;
  std::vector<V3> t_err;
  std::vector<M3> r_err;
  std::vector<bool> err_first;
};

Sample sample(std::mt19937_64& rng, const RawModel& raw, const std::vector<double>& lo, const std::vector<double>& hi,
              int kind) {
  Sample s;
  s.q.resize(lo.size());
  for (std::size_t i = 0; i < lo.size(); ++i) {
    if (kind == 0 || (kind == 1 && chance(rng, 0.7))) {
      s.q[i] = chance(rng, 0.5) ? lo[i] : hi[i];
    } else {
      const double w = hi[i] - lo[i];
      s.q[i] = std::isfinite(w) ? lo[i] + uniform(rng, 0, 1) * w : uniform(rng, lo[i], 0) + uniform(rng, 0, hi[i]);
      s.q[i] = std::clamp(s.q[i], lo[i], hi[i]);
    }
  }
  for (const RawJoint& j : raw.joints) {
    const double f = chance(rng, 0.7) ? 1.0 : uniform(rng, 0, 1);
    const Eigen::Vector3d u = testing::randomUnit(rng);
    const V3 ul = u.cast<Real>();
    s.t_err.push_back(j.type == JointType::Translation3d ? V3(ul * Real(j.error * f)) : V3::Zero());
    s.r_err.push_back(j.type == JointType::Rotation3d ? rodrigues(ul, Real(j.error * f)) : M3::Identity());
    s.err_first.push_back(chance(rng, 0.5));
  }
  return s;
}

// The body's core points in frame `top` (an ancestor of its frame), composed top-down.
std::vector<Eigen::Vector3d> pointsIn(const RawModel& raw, const Sample& s, int body, int top, double& scale) {
  std::vector<int> chain;
  for (int f = raw.bodies[body].frame; f != top; f = raw.joints[f].parent) chain.push_back(f);
  M3 rot = M3::Identity();
  V3 trans = V3::Zero();
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const RawJoint& j = raw.joints[*it];
    const M3 o_rot = rpy(j.rpy[0], j.rpy[1], j.rpy[2]);
    const V3 o_t(j.xyz[0], j.xyz[1], j.xyz[2]);
    const V3 axis = V3(j.axis[0], j.axis[1], j.axis[2]).normalized();
    const double* q = s.q.data() + j.offset;
    M3 m_rot = M3::Identity();
    V3 m_t = V3::Zero();
    switch (j.type) {
      case JointType::Fixed:
        break;
      case JointType::Revolute:
        m_rot = rodrigues(axis, q[0]);
        break;
      case JointType::Prismatic:
        m_t = axis * Real(q[0]);
        break;
      case JointType::Translation3d:
        m_t = V3(q[0], q[1], q[2]) + s.t_err[*it];
        break;
      case JointType::Rotation3d: {
        const M3 measured = rotationVector(V3(q[0], q[1], q[2]));
        m_rot = s.err_first[*it] ? M3(measured * s.r_err[*it]) : M3(s.r_err[*it] * measured);
        break;
      }
    }
    // x_parent = o_rot (m_rot x + m_t) + o_t
    trans = trans + rot * (o_rot * m_t + o_t);
    rot = rot * o_rot * m_rot;
  }
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : raw.bodies[body].points) {
    const V3 x = rot * p.cast<Real>() + trans;
    out.push_back(x.cast<double>());
    scale = std::max(scale, static_cast<double>(x.cwiseAbs().maxCoeff()));
  }
  return out;
}

struct Tally {
  long cases = 0, failed_status = 0, checks = 0, positive = 0, queries = 0;
};

// Runs one case; false (with a reason) on a violation.
bool runCase(std::uint64_t seed, Tally& tally, std::string& why) {
  std::mt19937_64 rng(seed);
  const RawModel raw = generate(rng);
  Model m;
  try {
    m = parseModel(raw.yaml, "generated");
  } catch (const ModelError& e) {
    why = std::string("generated model refused: ") + e.what() + "\n" + raw.yaml;
    return false;
  }
  std::vector<double> lower, upper;
  extremeBox(rng, m, lower, upper);
  ++tally.cases;
  const int np = static_cast<int>(m.pairs.size());
  // Every query type, on a fresh checker and on one that carries its table over.
  Checker reused(m);
  struct Answer {
    QueryType type;
    Status status;
    bool collision;
    double min_distance;
    std::vector<PairDistance> pairs;
  };
  std::vector<Answer> answers;
  for (int t = 0; t < 4; ++t) {
    for (int fresh = 0; fresh < 2; ++fresh) {
      Checker own(m);
      Checker& c = fresh ? own : reused;
      QueryOptions opt;
      opt.type = static_cast<QueryType>(t);
      opt.n = 1 + uniformInt(rng, 0, std::max(0, np - 1));
      opt.exact_below = fresh ? std::numeric_limits<double>::infinity() : -1.0;
      const QueryResult& r = c.query(lower, upper, opt);
      answers.push_back({r.type, r.status, r.collision, r.min_distance, {r.pairs.begin(), r.pairs.end()}});
      ++tally.queries;
      if (r.status != Status::Ok) {
        ++tally.failed_status;
        if (!r.collision || r.min_distance != 0.0) {
          why = "a failed status must report a collision at distance 0";
          return false;
        }
      }
    }
  }
  const double margin = m.safety_margin;
  std::vector<double> truth_min(np, INFINITY), tol(np, 0.0);
  for (int s = 0; s < 24; ++s) {
    const Sample smp = sample(rng, raw, lower, upper, s % 3);
    for (int p = 0; p < np; ++p) {
      const BodyPair& pair = m.pairs[p];
      double scale = 1.0;
      const auto a = pointsIn(raw, smp, pair.a, pair.lca, scale);
      const auto b = pointsIn(raw, smp, pair.b, pair.lca, scale);
      const double ra = raw.bodies[pair.a].radius, rb = raw.bodies[pair.b].radius;
      // Rounding of the points to double (and of the oracle) at this magnitude.
      tol[p] = std::max(tol[p], 1e-12 + 1e-15 * (scale + ra + rb));
      truth_min[p] = std::min(truth_min[p], static_cast<double>(testing::referenceSschDistance(a, ra, b, rb)));
    }
  }
  for (const Answer& ans : answers) {
    if (ans.status != Status::Ok) continue;
    for (const PairDistance& pd : ans.pairs) {
      ++tally.checks;
      if (pd.distance > 0.0) ++tally.positive;
      if (pd.distance > truth_min[pd.pair] + tol[pd.pair]) {
        const BodyPair& pair = m.pairs[pd.pair];
        why = std::string(toString(ans.type)) + ": pair b" + std::to_string(pair.a) + "-b" + std::to_string(pair.b) +
              " bound " + num(pd.distance) + " > sampled distance " + num(truth_min[pd.pair]) + "\n" + raw.yaml;
        return false;
      }
    }
    for (int p = 0; p < np; ++p) {
      if (ans.min_distance > truth_min[p] + tol[p]) {
        why = std::string(toString(ans.type)) + ": min_distance " + num(ans.min_distance) + " > sampled distance " +
              num(truth_min[p]) + "\n" + raw.yaml;
        return false;
      }
      if (!ans.collision && truth_min[p] + tol[p] <= margin) {
        why = std::string(toString(ans.type)) + ": 'clear' although a sampled distance is " + num(truth_min[p]) +
              " <= margin " + num(margin) + "\n" + raw.yaml;
        return false;
      }
    }
  }
  return true;
}

TEST(Extremes, BoundsStayConservativeAtTheExtremes) {
  const long single = envOr("KCCD_SEED", -1);
  const long cases = single >= 0 ? 1 : std::max(1L, envOr("KCCD_SOAK", 50000) / 10);
  Tally tally;
  long failures = 0;
  for (long i = 0; i < cases && failures < 5; ++i) {
    const std::uint64_t seed =
        single >= 0 ? static_cast<std::uint64_t>(single) : 0x657874 + static_cast<std::uint64_t>(i);
    std::string why;
    if (!runCase(seed, tally, why)) {
      ++failures;
      ADD_FAILURE() << "seed " << seed << " (rerun with KCCD_SEED=" << seed << "): " << why;
    }
  }
  std::cout << "[ property ] " << tally.cases << " extreme cases, " << tally.queries << " queries ("
            << tally.failed_status << " answered with an unsafe status), " << tally.checks
            << " reported bounds checked, " << tally.positive << " of them positive\n";
  EXPECT_EQ(failures, 0);
  if (single < 0) {
    EXPECT_GT(tally.positive, tally.checks / 10);       // most answers are not trivially 0
    EXPECT_LT(tally.failed_status, tally.queries / 5);  // and most are answers, not refusals
  }
}

// The cases the issue reported, as plain regressions: each collides at some angle in the box.
Model oneRevolute(const std::string& axis) {
  return parseModel("kccd: 1\nsafety_margin: 0.02\njoints: [{name: r, parent: world, type: revolute, axis: " + axis +
                        "}]\nbodies:\n  - {name: b, frame: world, points: [[1, 0, 0]], radius: 0.1}\n"
                        "  - {name: c, frame: r, points: [[0, 1.1, 0]], radius: 0.1}\n",
                    "regression");
}

TEST(Extremes, HugeRevoluteIntervalsAreNotClear) {
  const Model m = oneRevolute("[0, 0, 1]");
  Checker c(m);
  const double boxes[][2] = {{-1e17, 1e17},    {1e17, 1.00000000001e17},     {-3.4e38, 3.4e38},
                             {2e16, 2e16 + 8}, {1e300, 1e300 * (1 + 1e-15)}, {-1e9 - 4, -1e9 + 4}};
  for (const auto& box : boxes) {
    const std::vector<double> lo{box[0]}, hi{box[1]};
    const QueryResult& r = c.query(lo, hi, {});
    EXPECT_EQ(r.status, Status::Ok);
    EXPECT_TRUE(r.collision) << "[" << box[0] << ", " << box[1] << "] reported clear at " << r.min_distance;
  }
  // A narrow interval far out is still tight: at q = 1e9 (mod 2 pi) the bodies are apart.
  const double q = 1e9;
  const double angle = std::atan2(std::sin(q), std::cos(q));
  const std::vector<double> at{q};
  const double d = c.query(at, at, {.type = QueryType::Closest}).min_distance;
  const double expected = std::hypot(1.0 + 1.1 * std::sin(angle), 1.1 * std::cos(angle)) - 0.2;
  ASSERT_GT(expected, 0.03);  // q = 1e9 is 0.577 rad mod 2 pi: apart
  EXPECT_NEAR(d, expected, 1e-9);
}

TEST(Extremes, OverflowingAxisComponentsKeepTheirDirection) {
  const Model huge = oneRevolute("[1e200, 1e200, 0]");
  const Model plain = oneRevolute("[1, 1, 0]");
  const Model tiny = oneRevolute("[1e-150, 1e-150, 0]");
  EXPECT_NEAR(huge.joints[0].axis.x(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(tiny.joints[0].axis.y(), std::sqrt(0.5), 1e-15);
  for (double q : {-1.5707963, 0.0, 2.0, 3.0}) {
    const std::vector<double> at{q};
    Checker a(huge), b(plain), c(tiny);
    EXPECT_DOUBLE_EQ(a.query(at, at, {.type = QueryType::Distances}).min_distance,
                     b.query(at, at, {.type = QueryType::Distances}).min_distance);
    EXPECT_DOUBLE_EQ(c.query(at, at, {.type = QueryType::Distances}).min_distance,
                     b.query(at, at, {.type = QueryType::Distances}).min_distance);
  }
  EXPECT_THROW(oneRevolute("[0, 0, 0]"), ModelError);
}

#ifdef KCCD_WITH_MODELLING
// `kccd pairs` proofs at the extremes: a pair proven "never" must stay beyond the margin at every
// configuration the file's limits allow, however those limits are written.
Sample sampleLimits(std::mt19937_64& rng, const RawModel& raw, int state_size) {
  std::vector<double> lo(state_size, 0.0), hi(state_size, 0.0);
  for (const RawJoint& j : raw.joints) {
    for (int k = 0; k < j.dof; ++k) {
      const int s = j.offset + k;
      if (j.has_limits) {
        lo[s] = j.limits[0], hi[s] = j.limits[1];
      } else if (j.type == JointType::Revolute || j.type == JointType::Rotation3d) {
        // Any angle: a full turn, or far out.
        const double c = chance(rng, 0.3) ? signedPow10(rng, 0, 300) : uniform(rng, -3.2, 3.2);
        lo[s] = hi[s] = c;
      }
    }
  }
  return sample(rng, raw, lo, hi, uniformInt(rng, 0, 2));
}

TEST(Extremes, PairProofsHoldOverTheWholeRange) {
  const long cases = std::max(1L, envOr("KCCD_SOAK", 50000) / 250);
  long never = 0, checks = 0, violations = 0;
  for (long i = 0; i < cases && violations < 5; ++i) {
    const std::uint64_t seed = 0x70616972 + static_cast<std::uint64_t>(i);
    std::mt19937_64 rng(seed);
    const RawModel raw = generate(rng);
    const Model m = parseModel(raw.yaml, "generated");
    const auto reports = modelling::provePairs(m, {.max_boxes = 200});
    for (const auto& r : reports) {
      if (r.verdict != modelling::Verdict::Never) continue;
      ++never;
      for (int s = 0; s < 200; ++s) {
        const Sample smp = sampleLimits(rng, raw, m.stateSize());
        double scale = 1.0;
        const auto a = pointsIn(raw, smp, r.a, r.lca, scale);
        const auto b = pointsIn(raw, smp, r.b, r.lca, scale);
        const double ra = raw.bodies[r.a].radius, rb = raw.bodies[r.b].radius;
        const double truth = static_cast<double>(testing::referenceSschDistance(a, ra, b, rb));
        ++checks;
        if (truth + 1e-12 + 1e-15 * (scale + ra + rb) <= m.safety_margin ||
            truth + 1e-12 + 1e-15 * (scale + ra + rb) < r.bound) {
          ++violations;
          ADD_FAILURE() << "seed " << seed << ": pair b" << r.a << "-b" << r.b << " proven never (bound " << r.bound
                        << ") but a configuration within the limits is at " << truth << "\n"
                        << raw.yaml;
          break;
        }
      }
    }
  }
  std::cout << "[ property ] " << cases << " models, " << never << " pairs proven never, " << checks
            << " configurations checked\n";
  EXPECT_EQ(violations, 0);
  EXPECT_GT(never, cases / 4);
}
#endif

}  // namespace
}  // namespace kccd
