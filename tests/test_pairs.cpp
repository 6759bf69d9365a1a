// `kccd pairs` proofs against dense sampling with independent kinematics and distances.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "kccd/checker.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/pair_survey.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "kccd/modelling/yaml_edit.hpp"
#include "support/random_model.hpp"
#include "support/reference_distance.hpp"

namespace km = kccd::modelling;
using kccd::Model;
using kccd::Vec3;

namespace {

// Random limits for 1-DOF joints (some joints keep none).
void randomLimits(Model& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-2.0, 2.0), w(0.0, 2.5);
  for (kccd::Joint& j : m.joints) {
    if (j.type != kccd::JointType::Revolute && j.type != kccd::JointType::Prismatic) continue;
    if (j.type == kccd::JointType::Revolute && w(rng) < 0.4) {
      j.limits.reset();  // a full turn
      continue;
    }
    const double lo = u(rng);
    j.limits = std::array<double, 2>{lo, lo + w(rng) * (j.type == kccd::JointType::Prismatic ? 0.2 : 1.0)};
  }
}

double trueDistance(const Model& m, const std::vector<kccd::Pose>& poses, int a, int b) {
  return static_cast<double>(
      kccd::testing::referenceSschDistance(kccd::testing::worldPoints(m, poses, a), m.bodies[a].radius,
                                           kccd::testing::worldPoints(m, poses, b), m.bodies[b].radius));
}

// One configuration with no joint error realised: a recorded or drawn state.
kccd::testing::Sample pointSample(const Model& m, std::vector<double> q) {
  kccd::testing::Sample s;
  s.q = std::move(q);
  s.translation_error.assign(m.joints.size(), Vec3::Zero());
  s.rotation_error.assign(m.joints.size(), Eigen::Matrix3d::Identity());
  s.error_first.assign(m.joints.size(), false);
  return s;
}

}  // namespace

// A pair proven "never" must stay beyond the margin at every sampled configuration within the
// limits (corners, edges, interior, joint errors realised), and "always touching" must be within it.
TEST(Pairs, ProofsHoldUnderDenseSampling) {
  std::mt19937_64 rng(std::getenv("KCCD_SEED") ? std::stoull(std::getenv("KCCD_SEED")) : 20261121);
  int never = 0, touching = 0, meets = 0, samples = 0;
  for (int trial = 0; trial < 600; ++trial) {
    Model m = kccd::testing::randomModel(rng, 5, 4);
    randomLimits(m, rng);
    m.safety_margin = std::uniform_real_distribution<double>(0.0, 0.2)(rng);
    const std::vector<km::PairReport> reports = km::provePairs(m, {.max_boxes = 300});
    const auto ranges = km::jointRanges(m);
    std::vector<double> lower(m.stateSize()), upper(m.stateSize());
    for (int s = 0; s < m.stateSize(); ++s) {
      const bool bounded = !std::isnan(ranges[s][0]);
      lower[s] = bounded ? ranges[s][0] : -0.5;  // unbounded values: proofs never rely on them
      upper[s] = bounded ? ranges[s][1] : 0.5;
    }
    for (const km::PairReport& r : reports) {
      if (r.verdict == km::Verdict::Never) ++never;
      if (r.verdict == km::Verdict::AlwaysTouching) ++touching;
      if (r.verdict == km::Verdict::Meets) {
        ++meets;
        // The witness is a real configuration inside the limits.
        for (int s = 0; s < m.stateSize(); ++s)
          if (!std::isnan(ranges[s][0])) {
            EXPECT_GE(r.witness[s], ranges[s][0]);
            EXPECT_LE(r.witness[s], ranges[s][1]);
          }
      }
      if (r.verdict != km::Verdict::Never && r.verdict != km::Verdict::AlwaysTouching) continue;
      for (int k = 0; k < 60; ++k) {
        const kccd::testing::Sample s = kccd::testing::sampleBox(rng, m, lower, upper, k);
        const std::vector<kccd::Pose> poses = kccd::testing::jointPoses(m, s);
        const double d = trueDistance(m, poses, r.a, r.b);
        ++samples;
        if (r.verdict == km::Verdict::Never) {
          ASSERT_GT(d, m.safety_margin) << "trial " << trial << ": pair " << r.a << "-" << r.b
                                        << " proven never, but sampled distance " << d;
          ASSERT_GE(d, r.bound) << "trial " << trial << ": bound above a sampled distance";
        } else {
          ASSERT_LE(d, m.safety_margin + 1e-9) << "trial " << trial << ": pair " << r.a << "-" << r.b
                                               << " proven always touching, sampled distance " << d;
        }
      }
    }
  }
  RecordProperty("never", never);
  RecordProperty("always_touching", touching);
  RecordProperty("samples", samples);
  EXPECT_GT(never, 20);  // the test must exercise real proofs
  EXPECT_GT(meets, 20);
}

// Adjacent pairs joined by one revolute joint with fixed joints on either side (a hand on a
// flange, a link on a mounting plate): "always touching" must hold at every angle, sampled with
// the tests' own kinematics and distances.
TEST(Pairs, AlwaysTouchingThroughFixedJointsHoldsAtEveryAngle) {
  std::mt19937_64 rng(20261125);
  std::uniform_real_distribution<double> u(-1.0, 1.0), r01(0.0, 1.0);
  auto randomPose = [&](double reach) {
    kccd::Pose p = kccd::Pose::Identity();
    p.linear() = Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    p.translation() = reach * Vec3(u(rng), u(rng), u(rng));
    return p;
  };
  int touching = 0, other = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Model m;
    m.safety_margin = 0.05 * r01(rng);
    auto add = [&](const std::string& name, int parent, kccd::JointType type) {
      kccd::Joint j;
      j.name = name, j.parent = parent, j.type = type, j.origin = randomPose(0.3);
      j.axis = Vec3(u(rng), u(rng), u(rng)).normalized();
      m.joints.push_back(j);
      return static_cast<int>(m.joints.size()) - 1;
    };
    // The revolute joint under the world, under the base, or under a plate fixed to the base;
    // the parent body on the base or on a bracket fixed to it (a sibling branch).
    const int base = add("base", kccd::kWorld, kccd::JointType::Fixed);
    const int plate = add("plate", base, kccd::JointType::Fixed);
    const int bracket = add("bracket", base, kccd::JointType::Fixed);
    const int turn = add("turn",
                         trial % 3 == 0   ? kccd::kWorld
                         : trial % 3 == 1 ? base
                                          : plate,
                         kccd::JointType::Revolute);
    const int flange = add("flange", turn, kccd::JointType::Fixed);
    const int tool = add("tool", flange, kccd::JointType::Fixed);
    const int holder = trial % 2 ? base : bracket;
    auto world = [&](int frame) {  // the frame's pose in the world (all fixed)
      kccd::Pose p = kccd::Pose::Identity();
      for (int f = frame; f != kccd::kWorld; f = m.joints[f].parent) p = m.joints[f].origin * p;
      return p;
    };
    // Bodies around points of the axis (in their own frames), so that many pairs touch at every
    // angle and some do not.
    auto bodyNear = [&](const std::string& name, int frame, const kccd::Pose& axis_to_frame) {
      kccd::Body b;
      b.name = name, b.frame = frame, b.radius = 0.02 + 0.1 * r01(rng);
      const Vec3 on_axis = axis_to_frame * (0.3 * u(rng) * m.joints[turn].axis);
      for (int k = 0; k < 1 + trial % 4; ++k) b.points.push_back(on_axis + 0.15 * Vec3(u(rng), u(rng), u(rng)));
      m.bodies.push_back(b);
    };
    // The revolute joint's frame in the parent body's frame, and in the child body's.
    bodyNear("parent", holder, world(holder).inverse() * world(turn));
    bodyNear("child", tool, (m.joints[flange].origin * m.joints[tool].origin).inverse());
    m.finalize(true, {}, {});
    ASSERT_EQ(km::connection(m, 0, 1), km::Connection::Adjacent);
    const auto reports = km::provePairs(m, {.max_boxes = 50});
    ASSERT_EQ(reports.size(), 1u);
    if (reports[0].verdict != km::Verdict::AlwaysTouching) {
      ++other;
      continue;
    }
    ++touching;
    for (int k = 0; k <= 90; ++k) {
      const kccd::testing::Sample s = pointSample(m, {-std::numbers::pi + 2.0 * std::numbers::pi * k / 90.0});
      const double d = trueDistance(m, kccd::testing::jointPoses(m, s), 0, 1);
      ASSERT_LE(d, m.safety_margin + 1e-9) << "trial " << trial << " angle " << s.q[0];
    }
  }
  EXPECT_GT(touching, 40);
  EXPECT_GT(other, 40);
}

TEST(Pairs, DemoArm) {
  const Model m = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const auto reports = km::provePairs(m);
  auto find = [&](const std::string& a, const std::string& b) {
    for (const auto& r : reports)
      if ((m.bodies[r.a].name == a && m.bodies[r.b].name == b) || (m.bodies[r.a].name == b && m.bodies[r.b].name == a))
        return r;
    ADD_FAILURE() << a << "-" << b << " missing";
    return km::PairReport{};
  };
  // Joined at the shoulder axis: always in contact.
  EXPECT_EQ(find("shoulder", "upper_arm").verdict, km::Verdict::AlwaysTouching);
  // The base column is far from the table whatever the joints do.
  EXPECT_EQ(find("table", "shoulder").verdict, km::Verdict::Never);
  EXPECT_EQ(find("post", "forearm").verdict, km::Verdict::Meets);
}

namespace {

const km::PairReport& reportOf(const Model& m, const std::vector<km::PairReport>& reports, const std::string& a,
                               const std::string& b) {
  for (const auto& r : reports)
    if ((m.bodies[r.a].name == a && m.bodies[r.b].name == b) || (m.bodies[r.a].name == b && m.bodies[r.b].name == a))
      return r;
  throw std::runtime_error(a + "-" + b + " not reported");
}

std::string reasonOf(const Model& m, const std::string& a, const std::string& b) {
  for (const kccd::IgnoredPair& p : m.ignored)
    if ((m.bodies[p.a].name == a && m.bodies[p.b].name == b) || (m.bodies[p.a].name == b && m.bodies[p.b].name == a))
      return kccd::toString(p.reason);
  return "checked";
}

Model gripperArm(bool keep_adjacent) {
  km::ImportOptions opt;
  opt.fit = {
      .method = km::FitMethod::Points,
      .points = 4,
      .max_pieces = 1};  // fixed K = 4 fits, whole links: the rules under test, on the geometry they were written for
  opt.keep_adjacent = keep_adjacent;
  return kccd::parseModel(km::importUrdf(std::string(KCCD_TEST_DATA_DIR) + "/urdf/gripper_arm.urdf", opt), "gripper");
}

}  // namespace

// A Panda-like arm: the hand on fixed joints under a link without geometry (rigid with the last
// link), a camera bracket on a fixed joint, prismatic fingers. Import ignores rigid and adjacent
// pairs with their reasons, and keeps every pair with a body on a link between the two.
TEST(Pairs, RigidAndAdjacentPairsOfAGripperArm) {
  const Model m = gripperArm(false);
  EXPECT_EQ(reasonOf(m, "link3", "hand"), "rigid");  // fixed, fixed (flange has no geometry)
  EXPECT_EQ(reasonOf(m, "link3", "camera"), "rigid");
  EXPECT_EQ(reasonOf(m, "camera", "hand"), "rigid");  // siblings on fixed joints
  EXPECT_EQ(reasonOf(m, "base", "link1"), "adjacent");
  EXPECT_EQ(reasonOf(m, "link2", "link3"), "adjacent");
  EXPECT_EQ(reasonOf(m, "hand", "left_finger"), "adjacent");  // one prismatic joint
  EXPECT_EQ(reasonOf(m, "hand", "right_finger"), "adjacent");
  EXPECT_EQ(reasonOf(m, "link2", "hand"), "checked");                // link3 lies between
  EXPECT_EQ(reasonOf(m, "link3", "left_finger"), "checked");         // the hand lies between
  EXPECT_EQ(reasonOf(m, "left_finger", "right_finger"), "checked");  // two moving joints
  EXPECT_EQ(reasonOf(m, "base", "link2"), "checked");
  EXPECT_EQ(m.ignored.size(), 8u);
  EXPECT_EQ(m.pairs.size(), 28u - 8u);

  const Model kept = gripperArm(true);
  EXPECT_EQ(kept.ignored.size(), 3u);  // the rigid ones only
  for (const kccd::IgnoredPair& p : kept.ignored) EXPECT_EQ(p.reason, kccd::IgnoreReason::Rigid);

  // kccd pairs decides rigid pairs exactly: their one distance, never "meets".
  const auto reports = km::provePairs(m);
  const std::vector<kccd::Pose> poses =
      kccd::testing::jointPoses(m, pointSample(m, std::vector<double>(m.stateSize(), 0.0)));
  int rigid = 0;
  for (const auto& r : reports) {
    EXPECT_EQ(r.rigid, km::connection(m, r.a, r.b) == km::Connection::Rigid);
    if (!r.rigid) continue;
    ++rigid;
    const double d = trueDistance(m, poses, r.a, r.b);
    EXPECT_NE(r.verdict, km::Verdict::Meets);
    EXPECT_EQ(r.verdict, d > m.safety_margin ? km::Verdict::Never : km::Verdict::AlwaysTouching);
    EXPECT_NEAR(r.bound, d, 1e-9) << m.bodies[r.a].name << "-" << m.bodies[r.b].name;
  }
  EXPECT_EQ(rigid, 3);
  EXPECT_EQ(reportOf(m, reports, "link3", "hand").verdict, km::Verdict::AlwaysTouching);
  EXPECT_EQ(reportOf(m, reports, "link3", "camera").verdict, km::Verdict::Never);
  EXPECT_EQ(reportOf(m, reports, "link1", "link2").verdict, km::Verdict::AlwaysTouching);  // shared axis point

  // The ignore list: reasons from the proofs, adjacent pairs that meet ignored as adjacent.
  const km::IgnorePlan plan = km::ignoreList(m, reports);
  EXPECT_TRUE(plan.dropped.empty());
  auto planned = [&](const std::string& a, const std::string& b) {
    for (const auto& e : plan.ignore)
      if ((e.a == a && e.b == b) || (e.a == b && e.b == a)) return std::string(kccd::toString(e.reason));
    return std::string("checked");
  };
  EXPECT_EQ(planned("link3", "hand"), "rigid");
  EXPECT_EQ(planned("hand", "left_finger"), "adjacent");
  EXPECT_EQ(planned("link1", "link2"), "always_touching");
  EXPECT_EQ(planned("left_finger", "right_finger"),
            reportOf(m, reports, "left_finger", "right_finger").verdict == km::Verdict::Never ? "never" : "checked");
  const km::IgnorePlan keep = km::ignoreList(m, reports, {.keep_adjacent = true});
  for (const auto& e : keep.ignore) EXPECT_NE(e.reason, kccd::IgnoreReason::Adjacent);
  EXPECT_EQ(keep.dropped.size(), 2u);  // the fingers' adjacent entries of the file: checked again
}

// Reasons are read, kept and written back; an entry whose proof no longer holds is dropped;
// a reason that is not one of the words is one line naming the place.
TEST(Pairs, IgnoreReasonsRoundTripAndStaleProofsAreDropped) {
  const std::string text =
      "kccd: 1\nsafety_margin: 0.01\njoints:\n"
      "  - {name: j, parent: world, type: revolute, axis: [0, 0, 1], limits: [-1, 1]}\n"
      "bodies:\n"
      "  - {name: a, frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
      "  - {name: b, frame: j, points: [[0.5, 0, 0]], radius: 0.1}\n"
      "  - {name: c, frame: j, points: [[-0.5, 0, 0]], radius: 0.1}\n"
      "pairs:\n  ignore: [[a, b, never], [a, c, srdf]]\n";
  const Model m = kccd::parseModel(text, "m.yaml");
  ASSERT_EQ(m.ignored.size(), 2u);
  EXPECT_EQ(m.ignored[0].reason, kccd::IgnoreReason::Never);
  EXPECT_EQ(m.ignored[1].reason, kccd::IgnoreReason::Srdf);
  EXPECT_TRUE(m.pairs.empty());
  // a - b and a - c are 0.3 m apart at every angle: "never" stands; with a margin of 0.35 m it
  // does not and the entry is dropped (adjacent pairs kept: a and b are adjacent), while the SRDF's stays.
  const km::IgnorePlan plan = km::ignoreList(m, km::provePairs(m, {.margin = 0.35}), {.keep_adjacent = true});
  ASSERT_EQ(plan.dropped.size(), 1u);
  EXPECT_EQ(plan.dropped[0].reason, kccd::IgnoreReason::Never);
  ASSERT_EQ(plan.ignore.size(), 1u);
  EXPECT_EQ(plan.ignore[0].reason, kccd::IgnoreReason::Srdf);
  const std::string written = km::withIgnoreList(text, "m.yaml", km::ignoreList(m, km::provePairs(m)).ignore);
  EXPECT_NE(written.find("[a, b, never]"), std::string::npos) << written;
  EXPECT_NE(written.find("[a, c, srdf]"), std::string::npos) << written;  // the SRDF's decision keeps its word
  EXPECT_EQ(kccd::parseModel(written, "w").ignored.size(), 2u);
  try {
    (void)kccd::parseModel(text.substr(0, text.find("ignore:")) + "ignore: [[a, b, nearby]]\n", "bad.yaml");
    ADD_FAILURE() << "an unknown reason was accepted";
  } catch (const kccd::ModelError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.yaml:10:", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("pairs.ignore[0].reason: unknown reason 'nearby'"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)kccd::parseModel(text.substr(0, text.find("ignore:")) + "include: [[a, b, never]]\n", "b"),
               kccd::ModelError);
}

// Ignoring pairs by rule takes them out of the checks and changes nothing else: every pair kept
// gets the same bound, bit for bit, over random trees and boxes.
TEST(Pairs, AnIgnoredPairNeverChangesTheBoundOfAPairKept) {
  std::mt19937_64 rng(20261125);
  int compared = 0, ignored = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Model all = kccd::testing::randomModel(rng, 6, 5);
    Model fewer = all;
    std::vector<std::array<int, 2>> ignore;
    for (const auto& e : km::structuralIgnores(all).ignore) ignore.push_back({all.bodyIndex(e.a), all.bodyIndex(e.b)});
    fewer.finalize(true, ignore, {});
    ignored += static_cast<int>(all.pairs.size() - fewer.pairs.size());
    kccd::Checker ca(all), cf(fewer);
    std::vector<double> lower, upper;
    for (int box = 0; box < 4; ++box) {
      kccd::testing::randomBox(rng, all, lower, upper);
      const kccd::QueryOptions q{.type = kccd::QueryType::Distances};
      const kccd::QueryResult& ra = ca.query(lower, upper, q);
      const kccd::QueryResult& rf = cf.query(lower, upper, q);
      ASSERT_EQ(ra.status, rf.status);
      for (const kccd::PairDistance& d : rf.pairs) {
        const kccd::BodyPair& p = fewer.pairs[d.pair];
        for (const kccd::PairDistance& e : ra.pairs)
          if (all.pairs[e.pair].a == p.a && all.pairs[e.pair].b == p.b) {
            ASSERT_EQ(d.distance, e.distance) << "trial " << trial << " pair " << p.a << "-" << p.b;
            ++compared;
          }
      }
    }
  }
  EXPECT_GT(ignored, 100);
  EXPECT_GT(compared, 1000);
}

// The survey of a state log counts, per pair, the rows within the margin and the closest row,
// against an independent distance at every row (forward kinematics and distances of the tests'
// own reference code).
TEST(PairSurvey, CountsAndClosestAgreeWithIndependentDistances) {
  std::mt19937_64 rng(7);
  int within = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Model m = kccd::testing::randomModel(rng, 5, 4);
    for (kccd::Joint& j : m.joints) j.error = 0.0;  // a recorded state is one configuration
    // A budget that keeps every point (as an import's does): the bound at one configuration is
    // then the distance; a smaller one covers dropped points by a larger radius.
    for (const kccd::Body& b : m.bodies) m.point_budget = std::max(m.point_budget, static_cast<int>(b.points.size()));
    m.safety_margin = std::uniform_real_distribution<double>(0.0, 0.3)(rng);
    if (m.pairs.empty() || m.stateSize() == 0) continue;
    kccd::StateLog log;
    log.names = m.stateNames();
    log.circular.assign(m.stateSize(), 0);
    log.logged_velocity.assign(m.stateSize(), 0);
    std::uniform_real_distribution<double> angle(-3.0, 3.0);
    for (int row = 0; row < 50; ++row) {
      log.times.push_back(0.01 * row);
      for (int s = 0; s < m.stateSize(); ++s) log.values.push_back(0.3 * angle(rng));
    }
    const km::Survey survey = km::surveyStates(m, log, {.time_offset = 0.5});
    ASSERT_EQ(survey.samples, 50u);
    ASSERT_EQ(survey.pairs.size(), m.pairs.size());
    std::vector<std::size_t> count(m.pairs.size(), 0);
    std::vector<double> closest(m.pairs.size(), INFINITY), second(m.pairs.size(), INFINITY), at(m.pairs.size(), 0.0);
    std::size_t red = 0;
    bool borderline = false;
    for (int row = 0; row < 50; ++row) {
      const auto poses =
          kccd::testing::jointPoses(m, pointSample(m, std::vector<double>(log.row(row).begin(), log.row(row).end())));
      bool any = false;
      for (std::size_t p = 0; p < m.pairs.size(); ++p) {
        const double d = trueDistance(m, poses, m.pairs[p].a, m.pairs[p].b);
        borderline = borderline || std::abs(d - m.safety_margin) < 1e-7;
        if (d <= m.safety_margin) ++count[p], any = true;
        if (d < closest[p])
          second[p] = closest[p], closest[p] = d, at[p] = log.times[row] - 0.5;
        else
          second[p] = std::min(second[p], d);
      }
      red += any;
    }
    if (borderline) continue;  // a row on the margin itself: either count is right
    EXPECT_EQ(survey.samples_within, red) << "trial " << trial;
    for (std::size_t p = 0; p < m.pairs.size(); ++p) {
      const km::PairSurvey& s = survey.pairs[p];
      EXPECT_EQ(s.within, count[p]) << "trial " << trial << " pair " << p;
      EXPECT_LE(s.min_distance, std::max(0.0, closest[p]) + 1e-9);  // a lower bound
      EXPECT_NEAR(s.min_distance, std::max(0.0, closest[p]), 1e-6) << "trial " << trial << " pair " << p;
      if (closest[p] > 1e-6 && second[p] - closest[p] > 1e-6) {  // one closest row: its time, video clock
        EXPECT_DOUBLE_EQ(s.min_time, at[p]) << "trial " << trial << " pair " << p;
      }
      within += static_cast<int>(s.within);
    }
  }
  EXPECT_GT(within, 50);
}

// `--random N`: N states inside the joint ranges, one per time 0 ... N-1, the same for the same seed.
TEST(PairSurvey, RandomStatesStayInsideTheLimits) {
  const Model m = kccd::loadModel(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const kccd::StateLog log = km::randomStates(m, 200, 7);
  ASSERT_EQ(log.rows(), 200u);
  EXPECT_EQ(log.names, m.stateNames());
  const auto ranges = km::jointRanges(m);
  std::vector<double> lo(ranges.size(), INFINITY), hi(ranges.size(), -INFINITY);
  for (std::size_t row = 0; row < log.rows(); ++row) {
    EXPECT_EQ(log.times[row], static_cast<double>(row));
    for (std::size_t k = 0; k < ranges.size(); ++k) {
      const double v = log.row(row)[k];
      EXPECT_GE(v, ranges[k][0]);
      EXPECT_LE(v, ranges[k][1]);
      lo[k] = std::min(lo[k], v), hi[k] = std::max(hi[k], v);
    }
  }
  for (std::size_t k = 0; k < ranges.size(); ++k)  // spread over the range, not stuck at a value
    EXPECT_GT(hi[k] - lo[k], 0.8 * (ranges[k][1] - ranges[k][0])) << k;
  EXPECT_EQ(km::randomStates(m, 200, 7).values, log.values);
  EXPECT_NE(km::randomStates(m, 200, 8).values, log.values);
}

// A survey's pairs by concern: most often within the margin, then the closest, ties in survey order.
TEST(PairSurvey, ByConcernOrdersByCountThenDistance) {
  km::Survey s;
  const std::pair<std::size_t, double> pairs[] = {{0, 0.5}, {3, 0.2}, {3, 0.1}, {0, 0.05}, {3, 0.1}};
  for (const auto& [within, distance] : pairs) {
    km::PairSurvey p;
    p.within = within;
    p.min_distance = distance;
    s.pairs.push_back(p);
  }
  const std::vector<const km::PairSurvey*> order = km::byConcern(s.pairs);
  const std::vector<const km::PairSurvey*> expected{&s.pairs[2], &s.pairs[4], &s.pairs[1], &s.pairs[3], &s.pairs[0]};
  EXPECT_EQ(order, expected);
}

// What `kccd pairs` says of each pair, from the library: the reason it is ignored now and after
// the plan, the verdict in words, and the counts.
TEST(Pairs, ReasonsNotesAndCountsOfAGripperArm) {
  const Model m = gripperArm(false);
  const auto reports = km::provePairs(m);
  const km::IgnorePlan plan = km::ignoreList(m, reports);
  for (const auto& r : reports) {
    const std::string a = m.bodies[r.a].name, b = m.bodies[r.b].name;
    if (!r.checked) {
      EXPECT_EQ(km::currentIgnoreReason(m, r.a, r.b), reasonOf(m, a, b)) << a << "-" << b;
    }
    EXPECT_EQ(km::currentIgnoreReason(m, r.a, r.b), km::currentIgnoreReason(m, r.b, r.a));
    const std::string planned = km::plannedIgnoreReason(plan, m, r.a, r.b);
    bool listed = false;
    for (const auto& e : plan.ignore)
      if ((e.a == a && e.b == b) || (e.a == b && e.b == a)) {
        listed = true;
        EXPECT_EQ(planned, kccd::toString(e.reason)) << a << "-" << b;
      }
    EXPECT_EQ(planned.empty(), !listed) << a << "-" << b;
  }
  EXPECT_EQ(km::plannedIgnoreReason(plan, m, reportOf(m, reports, "link3", "hand").a,
                                    reportOf(m, reports, "link3", "hand").b),
            "rigid");
  EXPECT_EQ(
      km::currentIgnoreReason(m, reportOf(m, reports, "link2", "hand").a, reportOf(m, reports, "link2", "hand").b),
      "not_included");  // checked: in no ignore entry

  const km::VerdictCounts c = km::countVerdicts(reports);
  EXPECT_EQ(c.rigid, 3);
  EXPECT_EQ(c.never + c.always_touching + c.meets + c.undecided + c.unbounded + c.rigid,
            static_cast<int>(reports.size()));
  int adjacent = 0, never = 0;
  for (const auto& r : reports) adjacent += r.adjacent, never += !r.rigid && r.verdict == km::Verdict::Never;
  EXPECT_EQ(c.adjacent, adjacent);
  EXPECT_EQ(c.never, never);

  const km::PairReport& rigid = reportOf(m, reports, "link3", "camera");
  EXPECT_EQ(km::verdictNote(rigid),
            "rigid (only fixed joints between them): a constant distance, never within the margin: ignore");
  km::PairReport proven = rigid;
  proven.rigid = false;
  proven.boxes = 12;
  EXPECT_EQ(km::verdictNote(proven), "proven in 12 boxes: safe to ignore");
  proven.verdict = km::Verdict::Undecided;
  EXPECT_EQ(km::verdictNote(proven), "no proof within 12 boxes: keep");
  EXPECT_EQ(km::verdictNote(reportOf(m, reports, "link3", "hand")),
            "rigid (only fixed joints between them): a constant distance, always within the margin: ignore");
}
