// Forward kinematics at one configuration against the independent kinematics of the tests, and
// against the checker's own point-state volumes (what is drawn is what is checked).
#include <random>

#include <gtest/gtest.h>

#include "kccd/checker.hpp"
#include "kccd/kinematics.hpp"
#include "support/random_model.hpp"

using namespace kccd;

TEST(Kinematics, MatchesIndependentKinematicsAndCheckedVolumes) {
  std::mt19937_64 rng(4242);
  int bodies_checked = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Model m = kccd::testing::randomModel(rng, 6, 4);
    for (Joint& j : m.joints) j.error = 0.0;  // errors grow volumes: not a pose
    std::vector<double> lower, upper;
    kccd::testing::randomBox(rng, m, lower, upper);
    const std::vector<double> q = lower;  // a point state
    kccd::testing::Sample s = kccd::testing::sampleBox(rng, m, q, q, 0);
    for (auto& t : s.translation_error) t.setZero();
    for (auto& r : s.rotation_error) r.setIdentity();
    const std::vector<Pose> reference = kccd::testing::jointPoses(m, s);
    std::vector<Pose> poses(m.joints.size());
    ASSERT_TRUE(framePoses(m, s.q, poses));
    for (std::size_t j = 0; j < poses.size(); ++j)
      EXPECT_LT((poses[j].matrix() - reference[j].matrix()).norm(), 1e-9 * (1 + reference[j].translation().norm()))
          << "trial " << trial << " joint " << j;
    Checker checker(m);
    ASSERT_EQ(checker.query(s.q, s.q).status, Status::Ok);
    for (std::size_t b = 0; b < m.bodies.size(); ++b) {
      const SschView v = checker.sweptVolume(static_cast<int>(b), kWorld);
      const Pose& pose = framePose(poses, m.bodies[b].frame);
      // A body with more points than the model's point budget is checked as a reduced volume.
      if (v.points.size() != m.bodies[b].points.size()) continue;
      EXPECT_LE(v.radius - m.bodies[b].radius, 1e-9);  // at most a rounding guard
      for (std::size_t k = 0; k < v.points.size(); ++k)
        EXPECT_LT((v.points[k] - pose * m.bodies[b].points[k]).norm(), 1e-9 * (1 + v.points[k].norm()));
      ++bodies_checked;
    }
  }
  EXPECT_GT(bodies_checked, 1000);
}

TEST(Kinematics, RejectsBadInput) {
  Model m = parseModel(
      "kccd: 1\nname: t\njoints:\n  - {name: a, parent: world, type: revolute, axis: [0, 0, 1]}\n"
      "  - {name: b, parent: a, type: translation3d, error: 0.01}\n"
      "bodies:\n  - {name: x, frame: b, points: [[0, 0, 0]], radius: 0.1}\n",
      "inline");
  std::vector<Pose> poses(m.joints.size());
  EXPECT_FALSE(framePoses(m, std::vector<double>{0.1}, poses));
  EXPECT_FALSE(framePoses(m, std::vector<double>{0.1, 0, 0, NAN}, poses));
  std::vector<Pose> short_poses(1);
  EXPECT_FALSE(framePoses(m, std::vector<double>{0.1, 0, 0, 0}, short_poses));
  EXPECT_TRUE(framePoses(m, std::vector<double>{0.1, 1, 2, 3}, poses));
  EXPECT_NEAR((poses[1].translation() - Eigen::AngleAxisd(0.1, Vec3::UnitZ()) * Vec3(1, 2, 3)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(hasErrorBound(m, 1));
  EXPECT_FALSE(hasErrorBound(m, 0));
}
