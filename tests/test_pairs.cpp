// `kccd pairs` proofs against dense sampling with independent kinematics and distances.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "kccd/model.hpp"
#include "kccd/modelling/pair_proof.hpp"
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
  return static_cast<double>(kccd::testing::referenceSschDistance(kccd::testing::worldPoints(m, poses, a),
                                                                  m.bodies[a].radius,
                                                                  kccd::testing::worldPoints(m, poses, b),
                                                                  m.bodies[b].radius));
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
