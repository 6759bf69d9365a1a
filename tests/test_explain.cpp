// The closest configuration of a flagged pair: closed forms, the box, conservativeness against the
// Checker, verdicts, determinism, and `kccd query --explain`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "kccd/checker.hpp"
#include "kccd/distance.hpp"
#include "kccd/explain.hpp"
#include "support/random_model.hpp"

#ifdef KCCD_CLI
#include <nlohmann/json.hpp>

#include "support/run_program.hpp"
#endif

namespace kccd {
namespace {

// The coordinates of a point as YAML, to the last bit.
std::string yamlPoint(const Vec3& p) {
  std::ostringstream o;
  o << std::setprecision(17) << "[" << p.x() << ", " << p.y() << ", " << p.z() << "]";
  return o.str();
}

// A one-joint arm: a capsule of radius 0.05 from the z axis out to 1 m along x, turning about z,
// and a ball of radius 0.1 at `ball` in the world.
Model armAndBall(const Vec3& ball, const std::string& sweep = "accurate") {
  const std::string text = R"(kccd: 1
name: arm_and_ball
safety_margin: 0.01
joints:
  - {name: turn, parent: world, type: revolute, axis: [0, 0, 1], sweep: )" +
                           sweep + R"(}
bodies:
  - {name: arm, frame: turn, points: [[0, 0, 0], [1, 0, 0]], radius: 0.05}
  - {name: ball, frame: world, points: [)" +
                           yamlPoint(ball) + R"(], radius: 0.1}
)";
  return parseModel(text, "arm_and_ball.yaml");
}

// The distance between the arm at angle q and the ball (closed form).
double armBallDistance(const Vec3& ball, double q) {
  const Vec3 dir(std::cos(q), std::sin(q), 0.0);
  const double along = std::clamp(ball.dot(dir), 0.0, 1.0);
  return std::max(0.0, (ball - along * dir).norm() - 0.15);
}

// A planar arm of two 1 m links turning about z, and a ball of radius 0.1 at `ball`.
Model twoLinkArm(const Vec3& ball) {
  const std::string text = R"(kccd: 1
name: two_link
safety_margin: 0.01
joints:
  - {name: q1, parent: world, type: revolute, axis: [0, 0, 1]}
  - {name: q2, parent: q1, type: revolute, origin: {xyz: [1, 0, 0]}, axis: [0, 0, 1]}
bodies:
  - {name: link1, frame: q1, points: [[0.2, 0, 0], [0.8, 0, 0]], radius: 0.05}
  - {name: link2, frame: q2, points: [[0, 0, 0], [1, 0, 0]], radius: 0.05}
  - {name: ball, frame: world, points: [)" +
                           yamlPoint(ball) + R"(], radius: 0.1}
pairs:
  ignore: [[link1, link2], [link1, ball]]
)";
  return parseModel(text, "two_link.yaml");
}

int pairOf(const Model& m, const std::string& a, const std::string& b) {
  for (std::size_t i = 0; i < m.pairs.size(); ++i) {
    const std::string& na = m.bodies[static_cast<std::size_t>(m.pairs[i].a)].name;
    const std::string& nb = m.bodies[static_cast<std::size_t>(m.pairs[i].b)].name;
    if ((na == a && nb == b) || (na == b && nb == a)) return static_cast<int>(i);
  }
  ADD_FAILURE() << "no pair " << a << " - " << b;
  return 0;
}

void expectInside(const ClosestConfiguration& c, const std::vector<double>& lower, const std::vector<double>& upper) {
  ASSERT_EQ(c.state.size(), lower.size());
  for (std::size_t i = 0; i < lower.size(); ++i) {
    EXPECT_GE(c.state[i], lower[i]) << i;
    EXPECT_LE(c.state[i], upper[i]) << i;
  }
}

TEST(Explain, OneJointArmReachesTheClosedFormMinimum) {
  const Vec3 ball(0.5 * std::cos(1.0), 0.5 * std::sin(1.0), 0.3);
  const Model m = armAndBall(ball);
  // The ball's direction (1 rad) lies beyond the interval: the minimum is at its upper end.
  const std::vector<double> lower{0.0}, upper{0.6};
  const ClosestConfiguration c = closestConfiguration(m, 0, lower, upper);
  expectInside(c, lower, upper);
  EXPECT_NEAR(c.distance, armBallDistance(ball, 0.6), 1e-9);
  EXPECT_NEAR(c.state[0], 0.6, 1e-9);
  EXPECT_NEAR((c.point_a - c.point_b).norm(), c.distance, 1e-9);
  EXPECT_NEAR((c.point_b - ball).norm(), 0.1, 1e-9);  // on the ball's surface
  EXPECT_GT(c.evaluations, 0);
  // The interval holds the ball's direction: the arm passes under it, 0.3 m below its centre.
  const std::vector<double> wide_lower{-0.5}, wide_upper{2.0};
  const ClosestConfiguration w = closestConfiguration(m, 0, wide_lower, wide_upper);
  EXPECT_NEAR(w.distance, 0.3 - 0.15, 1e-9);
  EXPECT_NEAR(w.state[0], 1.0, 1e-6);
}

TEST(Explain, TwoLinkArmFindsTheStretchedPose) {
  // The ball 2.5 m out at 0.3 rad, beyond the arm's 2 m reach: the closest pose points the
  // stretched arm at it (q1 = 0.3, q2 = 0), 0.5 - 0.05 - 0.1 m away.
  const Vec3 ball(2.5 * std::cos(0.3), 2.5 * std::sin(0.3), 0.0);
  const Model m = twoLinkArm(ball);
  const std::vector<double> lower{-1.0, -0.5}, upper{1.0, 0.5};
  const ClosestConfiguration c = closestConfiguration(m, pairOf(m, "link2", "ball"), lower, upper);
  expectInside(c, lower, upper);
  EXPECT_NEAR(c.distance, 0.35, 1e-7);
  EXPECT_NEAR(c.state[0], 0.3, 1e-3);
  EXPECT_NEAR(c.state[1], 0.0, 1e-3);
}

TEST(Explain, PrismaticTranslationAndRotationJointsReachTheirMinima) {
  const Model m = parseModel(R"(kccd: 1
name: free_joints
safety_margin: 0.01
joints:
  - {name: slide, parent: world, type: prismatic, axis: [1, 0, 0]}
  - {name: pose, parent: world, type: translation3d, origin: {xyz: [5, 0, 0]}, error: 0.01}
  - {name: turn, parent: world, type: rotation3d, origin: {xyz: [-5, 0, 0]}, error: 0.01}
bodies:
  - {name: slider, frame: slide, points: [[0, 0, 0]], radius: 0.05}
  - {name: slide_ball, frame: world, points: [[1.5, 0.5, 0]], radius: 0.1}
  - {name: carried, frame: pose, points: [[0, 0, 0]], radius: 0.05}
  - {name: pose_ball, frame: world, points: [[6, 1, 1]], radius: 0.1}
  - {name: turned, frame: turn, points: [[1, 0, 0]], radius: 0.05}
  - {name: turn_ball, frame: world, points: [[-5, 1.2, 0.6]], radius: 0.1}
pairs:
  check: none
  include: [[slider, slide_ball], [carried, pose_ball], [turned, turn_ball]]
)",
                             "free_joints.yaml");
  // slide, pose.x/y/z, turn.x/y/z
  const std::vector<double> lower{0.0, 0.0, 0.0, 0.0, -0.2, -1.0, 0.0}, upper{2.0, 0.3, 0.3, 0.3, 0.2, 1.0, 2.0};
  // The slider passes the ball's foot at 1.5: 0.5 m from its centre.
  const ClosestConfiguration slide = closestConfiguration(m, pairOf(m, "slider", "slide_ball"), lower, upper);
  EXPECT_NEAR(slide.distance, 0.5 - 0.15, 1e-9);
  EXPECT_NEAR(slide.state[0], 1.5, 1e-6);
  // The carried ball goes to the box corner nearest (1, 1, 1) away.
  const ClosestConfiguration pose = closestConfiguration(m, pairOf(m, "carried", "pose_ball"), lower, upper);
  EXPECT_NEAR(pose.distance, std::sqrt(3.0) * 0.7 - 0.15, 1e-9);
  for (int i = 1; i <= 3; ++i) EXPECT_NEAR(pose.state[static_cast<std::size_t>(i)], 0.3, 1e-9);
  // The point 1 m from the rotation centre reaches the unit sphere's point towards (0, 1.2, 0.6),
  // a rotation by pi/2 about (0, -1, 2) / sqrt(5), inside the box.
  const ClosestConfiguration turn = closestConfiguration(m, pairOf(m, "turned", "turn_ball"), lower, upper);
  EXPECT_NEAR(turn.distance, std::sqrt(1.8) - 1.0 - 0.15, 1e-7);
  for (const ClosestConfiguration* c : {&slide, &pose, &turn}) expectInside(*c, lower, upper);
}

TEST(Explain, UnlimitedRevoluteIntervalsAreSearchedOverOneTurn) {
  const Vec3 ball(0.5 * std::cos(1.0), 0.5 * std::sin(1.0), 0.3);
  const Model m = armAndBall(ball);
  for (double limit : {3.4e38, 1e300, 100.0}) {
    const std::vector<double> lower{-limit}, upper{limit};
    const ClosestConfiguration c = closestConfiguration(m, 0, lower, upper);
    expectInside(c, lower, upper);
    EXPECT_NEAR(c.distance, 0.15, 1e-9) << limit;
    EXPECT_NEAR(std::remainder(c.state[0] - 1.0, 2.0 * std::numbers::pi), 0.0, 1e-6) << limit;
  }
  // An interval far from zero: the values stay inside it and finite.
  const std::vector<double> lower{1e20}, upper{3.4e38};
  const ClosestConfiguration far = closestConfiguration(m, 0, lower, upper);
  expectInside(far, lower, upper);
  EXPECT_TRUE(std::isfinite(far.distance));
  EXPECT_GE(far.distance, 0.15 - 1e-9);
}

TEST(Explain, VerdictsFollowBoundFoundAndMargin) {
  EXPECT_EQ(verdict(0.02, 0.03, 0.01), PairVerdict::Clear);
  EXPECT_EQ(verdict(0.0, 0.005, 0.01), PairVerdict::Real);
  EXPECT_EQ(verdict(0.0, 0.01, 0.01), PairVerdict::Real);
  EXPECT_EQ(verdict(0.0, 0.02, 0.01), PairVerdict::Possible);
  EXPECT_EQ(verdict(0.0, std::numeric_limits<double>::infinity(), 0.01), PairVerdict::Possible);
  EXPECT_EQ(verdict(0.0, std::nan(""), 0.01), PairVerdict::Possible);
  EXPECT_STREQ(toString(PairVerdict::Real), "real");
  EXPECT_STREQ(toString(PairVerdict::Possible), "possible");
}

TEST(Explain, ACollidingBoxIsReal) {
  // The ball in the arm's plane, 0.5 m out at 1 rad: the arm runs through it at q = 1.
  const Vec3 ball(0.5 * std::cos(1.0), 0.5 * std::sin(1.0), 0.0);
  const Model m = armAndBall(ball);
  const std::vector<double> lower{0.2}, upper{1.5};
  const std::vector<PairExplanation> e = explainFlagged(m, lower, upper);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].verdict, PairVerdict::Real);
  EXPECT_EQ(e[0].closest.distance, 0.0);
  EXPECT_LE(e[0].bound, e[0].closest.distance);
  EXPECT_NEAR(armBallDistance(ball, e[0].closest.state[0]), 0.0, 1e-12);  // the configuration proves it
  expectInside(e[0].closest, lower, upper);
}

TEST(Explain, AWideBoxThatOnlyLooksFlaggedIsPossible) {
  // The arm turns through 3.9 rad on the far side of the ball: its swept hull reaches the ball
  // across the chord of the arc, but the arm itself never comes nearer than 0.5 - 0.15 m.
  const Vec3 ball(0.5 * std::cos(1.0), 0.5 * std::sin(1.0), 0.0);
  const Model m = armAndBall(ball);
  const std::vector<double> lower{1.0 + 1.2}, upper{1.0 + 2.0 * std::numbers::pi - 1.2};
  const std::vector<PairExplanation> e = explainFlagged(m, lower, upper);
  ASSERT_EQ(e.size(), 1u) << "the Checker's bound is above the margin: the premise of this test fails";
  EXPECT_LE(e[0].bound, m.safety_margin);
  EXPECT_EQ(e[0].verdict, PairVerdict::Possible);
  EXPECT_NEAR(e[0].closest.distance, armBallDistance(ball, lower[0]), 1e-9);  // 0.5 sin(1.2) - 0.15
  expectInside(e[0].closest, lower, upper);
  // A narrow box around the arm's far position is clear.
  const std::vector<double> far_lower{3.0}, far_upper{3.2};
  EXPECT_TRUE(explainFlagged(m, far_lower, far_upper).empty());
}

TEST(Explain, SameSeedSameAnswer) {
  const Model m = loadModel(std::string(KCCD_DATA_DIR) + "/humanoid.yaml");
  std::vector<double> lower(static_cast<std::size_t>(m.stateSize())), upper(lower.size());
  for (std::size_t i = 0; i < lower.size(); ++i) {
    lower[i] = 0.1 + 0.05 * static_cast<double>(i % 3);
    upper[i] = lower[i] + 0.3;
  }
  SearchOptions options;
  options.seed = 7;
  for (int pair : {0, static_cast<int>(m.pairs.size()) / 2, static_cast<int>(m.pairs.size()) - 1}) {
    const ClosestConfiguration x = closestConfiguration(m, pair, lower, upper, options);
    const ClosestConfiguration y = closestConfiguration(m, pair, lower, upper, options);
    EXPECT_EQ(x.distance, y.distance) << pair;
    EXPECT_EQ(x.state, y.state) << pair;
    EXPECT_EQ(x.evaluations, y.evaluations) << pair;
    EXPECT_TRUE(x.point_a == y.point_a && x.point_b == y.point_b) << pair;
    expectInside(x, lower, upper);
  }
}

TEST(Explain, BadArgumentsThrow) {
  const Model m = armAndBall(Vec3(0.5, 0.5, 0.3));
  const std::vector<double> lower{0.0}, upper{1.0}, two{0.0, 1.0}, nan{std::nan("")};
  EXPECT_THROW(closestConfiguration(m, 1, lower, upper), std::invalid_argument);
  EXPECT_THROW(closestConfiguration(m, -1, lower, upper), std::invalid_argument);
  EXPECT_THROW(closestConfiguration(m, 0, two, upper), std::invalid_argument);
  EXPECT_THROW(closestConfiguration(m, 0, upper, lower), std::invalid_argument);
  EXPECT_THROW(closestConfiguration(m, 0, nan, upper), std::invalid_argument);
  SearchOptions none;
  none.starts = 0;
  EXPECT_THROW(closestConfiguration(m, 0, lower, upper, none), std::invalid_argument);
  EXPECT_THROW(explainFlagged(m, upper, lower), std::invalid_argument);
}

// The found configuration realises the found distance (forward kinematics written independently
// of libkccd), lies in the box, and is never closer than the Checker's lower bound for the box.
TEST(Explain, NeverBelowTheCheckersBoundOnRandomModels) {
  std::mt19937_64 rng(20261123);
  int pairs = 0, checked_models = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Model m = testing::randomModel(rng);
    std::vector<double> lower, upper;
    testing::randomBox(rng, m, lower, upper);
    Checker checker(m);
    QueryOptions q;
    q.type = QueryType::Distances;
    const QueryResult& r = checker.query(lower, upper, q);
    if (r.status != Status::Ok) continue;
    ++checked_models;
    SearchOptions options;
    options.starts = 4;
    options.seed = static_cast<std::uint64_t>(trial);
    for (const PairDistance& pd : r.pairs) {
      const ClosestConfiguration c = closestConfiguration(m, pd.pair, lower, upper, options);
      ++pairs;
      expectInside(c, lower, upper);
      ASSERT_FALSE(std::isnan(c.distance));
      EXPECT_GE(c.distance, pd.distance - 1e-9) << "trial " << trial << " pair " << pd.pair;
      // Independent forward kinematics at the found state, errors at zero.
      testing::Sample s;
      s.q = c.state;
      s.translation_error.assign(m.joints.size(), Vec3::Zero());
      s.rotation_error.assign(m.joints.size(), Eigen::Matrix3d::Identity());
      s.error_first.assign(m.joints.size(), false);
      const std::vector<Pose> poses = testing::jointPoses(m, s);
      const BodyPair& p = m.pairs[static_cast<std::size_t>(pd.pair)];
      const std::vector<Vec3> pa = testing::worldPoints(m, poses, p.a);
      const std::vector<Vec3> pb = testing::worldPoints(m, poses, p.b);
      const DistanceResult d = distance({pa, m.bodies[static_cast<std::size_t>(p.a)].radius},
                                        {pb, m.bodies[static_cast<std::size_t>(p.b)].radius});
      const double scale = 1.0 + pa.front().norm() + pb.front().norm();
      EXPECT_NEAR(c.distance, d.distance, 1e-9 * scale) << "trial " << trial << " pair " << pd.pair;
      if (c.distance > 0.0) {
        EXPECT_NEAR((c.point_a - c.point_b).norm(), c.distance, 1e-9 * scale);
      }
    }
  }
  EXPECT_GT(checked_models, 400);
  EXPECT_GT(pairs, 1200);
}

// Descent finds at least what its starts see: never worse than the box centre, and on one-joint
// arms within reach of a dense scan of the interval.
TEST(Explain, NoWorseThanADenseScanOnOneJoint) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 ball(u(rng), u(rng), 0.3 * u(rng));
    const Model m = armAndBall(ball);
    const double a = 3.0 * u(rng), width = 1.5 * (1.0 + u(rng));
    const std::vector<double> lower{a}, upper{a + width};
    const ClosestConfiguration c = closestConfiguration(m, 0, lower, upper);
    double scan = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= 2000; ++i) scan = std::min(scan, armBallDistance(ball, a + width * i / 2000.0));
    EXPECT_LE(c.distance, scan + 1e-9) << trial << " ball " << ball.transpose() << " [" << a << ", " << a + width
                                       << "] at " << c.state[0] << " evaluations " << c.evaluations;
    EXPECT_NEAR(c.distance, armBallDistance(ball, c.state[0]), 1e-9) << trial;
  }
}

#ifdef KCCD_CLI
using testing::Outcome;

Outcome runKccd(const std::string& args) { return testing::runProgram(std::string(KCCD_CLI) + " " + args, false); }

const std::string kDemo = std::string(KCCD_DATA_DIR) + "/demo_arm.yaml";
// The forearm sweeps down through the table in front of the robot.
const std::string kFlaggedBox = " --lower 0,0.6,-0.4 --upper 0.3,1.2,0.4";

TEST(Cli, QueryExplainJson) {
  const Outcome r = runKccd("query " + kDemo + kFlaggedBox + " --type distances --json --explain");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("explain"));
  const double margin = j["margin"].get<double>();
  std::size_t flagged = 0;
  for (const auto& p : j["pairs"]) flagged += p["distance"].get<double>() <= margin ? 1 : 0;
  ASSERT_GT(flagged, 0u);
  ASSERT_EQ(j["explain"].size(), flagged);
  bool real = false;
  for (const auto& e : j["explain"]) {
    for (const char* key : {"a", "b", "verdict"}) EXPECT_TRUE(e[key].is_string()) << key;
    EXPECT_LE(e["bound"].get<double>(), margin);
    EXPECT_GE(e["distance"].get<double>(), e["bound"].get<double>() - 1e-9);
    const std::string v = e["verdict"];
    EXPECT_EQ(v, e["distance"].get<double>() <= margin ? "real" : "possible");
    real = real || v == "real";
    ASSERT_EQ(e["state"].size(), 3u);
    const double lower[] = {0.0, 0.6, -0.4}, upper[] = {0.3, 1.2, 0.4};
    int i = 0;
    for (const char* name : {"shoulder_yaw", "shoulder_pitch", "elbow"}) {
      ASSERT_TRUE(e["state"][name].is_number()) << name;
      EXPECT_GE(e["state"][name].get<double>(), lower[i]) << name;
      EXPECT_LE(e["state"][name].get<double>(), upper[i]) << name;
      ++i;
    }
    EXPECT_EQ(e["point_a"].size(), 3u);
    EXPECT_EQ(e["point_b"].size(), 3u);
  }
  EXPECT_TRUE(real);
  // Without --explain the key is absent.
  EXPECT_FALSE(nlohmann::json::parse(runKccd("query " + kDemo + kFlaggedBox + " --json").out).contains("explain"));
}

TEST(Cli, QueryExplainText) {
  const Outcome r = runKccd("query " + kDemo + kFlaggedBox + " --explain");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("explain: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(": real"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("shoulder_yaw = "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("elbow = "), std::string::npos) << r.out;
  const Outcome help = runKccd("query --help");
  EXPECT_NE(help.out.find("--explain"), std::string::npos);
  EXPECT_NE(help.out.find("possible"), std::string::npos);
  // A bad box keeps the one-line contract.
  const Outcome bad = runKccd("query " + kDemo + " --state 0,0 --explain");
  EXPECT_EQ(bad.code, 2);
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
}
#endif

}  // namespace
}  // namespace kccd
