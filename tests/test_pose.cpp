// Camera pose from correspondences (kccd::calib::solvePose): accuracy on random distorted cameras,
// misclicked labels, honest sigmas, every degenerate input, exact data. Needs no images.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <set>
#include <string>

#include <opencv2/calib3d.hpp>

#include "kccd/calib/pose.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "support/cameras.hpp"

namespace {

using namespace kccd;
using namespace kccd::calib;
using kccd::testing::lookAt;
using kccd::testing::randomCamera;
using kccd::testing::rotationErrorDeg;

struct Scene {
  Camera truth;
  std::vector<Correspondence> points;  // exact pixels
};

std::vector<cv::Point2d> project(const Camera& c, const std::vector<cv::Point3d>& world) {
  std::vector<cv::Point2d> out;
  cv::projectPoints(world, c.rvec, c.tvec, c.camera_matrix, c.distortion, out);
  return out;
}

bool inFront(const Camera& c, const cv::Point3d& p) {
  cv::Matx33d r;
  cv::Rodrigues(c.rvec, r);
  return (r * cv::Vec3d(p.x, p.y, p.z) + c.tvec)[2] > 0.1;
}

// A random distorted camera that passes Camera::validate (some random lenses cannot be inverted).
Camera validCamera(std::mt19937_64& rng) {
  for (;;) {
    Camera c = randomCamera(rng, true);
    try {
      c.validate("random");
      return c;
    } catch (const CameraError&) {
    }
  }
}

// `n` points uniform in a cube of half-side `half` around the origin, in front of the camera and
// projecting inside the image (at least 5 px from its border).
Scene randomScene(std::mt19937_64& rng, int n = 12, double half = 0.4) {
  Scene s;
  s.truth = validCamera(rng);
  std::uniform_real_distribution<double> u(-half, half);
  while (static_cast<int>(s.points.size()) < n) {
    const cv::Point3d p(u(rng), u(rng), u(rng));
    if (!inFront(s.truth, p)) continue;
    const cv::Point2d q = project(s.truth, {p})[0];
    if (q.x < 5 || q.y < 5 || q.x > s.truth.width - 6 || q.y > s.truth.height - 6) continue;
    s.points.push_back({"p" + std::to_string(s.points.size()), q, p});
  }
  return s;
}

std::vector<Correspondence> withNoise(std::vector<Correspondence> pts, std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> g(0.0, sigma);
  for (auto& p : pts) p.pixel += cv::Point2d(g(rng), g(rng));
  return pts;
}

double positionError(const Camera& a, const Camera& b) {
  return cv::norm(kccd::testing::cameraCentre(a) - kccd::testing::cameraCentre(b));
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

Camera intrinsicsOf(const Camera& c) {
  Camera i = c;
  i.rvec = cv::Vec3d(0.3, -0.2, 0.1);  // ignored
  i.tvec = cv::Vec3d(5, 5, 5);
  return i;
}

// ---------------------------------------------------------------------------------------------
// Accuracy

TEST(CalibPose, RandomCamerasWithOnePixelNoise) {
  std::mt19937_64 rng(101);
  std::vector<double> rot, pos;
  int solved = 0;
  const int cases = 150;
  for (int c = 0; c < cases; ++c) {
    const Scene s = randomScene(rng);
    const PoseResult r = solvePose(intrinsicsOf(s.truth), withNoise(s.points, rng, 1.0));
    if (r.status != PoseStatus::Solved) {
      ADD_FAILURE() << "case " << c << ": " << r.message;
      continue;
    }
    ++solved;
    EXPECT_TRUE(r.rejected.empty()) << r.message;
    rot.push_back(rotationErrorDeg(r.camera.rvec, s.truth.rvec));
    pos.push_back(positionError(r.camera, s.truth));
  }
  std::printf("1 px noise, %d cameras: median rotation error %.3f deg, position error %.2f mm\n", solved, median(rot),
              1000 * median(pos));
  EXPECT_LT(median(rot), 0.8);  // measured 0.54 deg, 14 mm (320 x 240, f ~ 290 px, points within 0.4 m at ~1.5 m)
  EXPECT_LT(median(pos), 0.021);
}

TEST(CalibPose, ExactDataRecoversThePose) {
  std::mt19937_64 rng(7);
  for (int c = 0; c < 30; ++c) {
    const Scene s = randomScene(rng);
    const PoseResult r = solvePose(intrinsicsOf(s.truth), s.points);
    ASSERT_EQ(r.status, PoseStatus::Solved) << r.message;
    EXPECT_LT(cv::norm(r.camera.rvec - s.truth.rvec), 1e-6);
    EXPECT_LT(cv::norm(r.camera.tvec - s.truth.tvec), 1e-6);
    EXPECT_LT(*r.camera.reprojection_rms_px, 1e-6);
    EXPECT_LT(*r.camera.rotation_sigma_deg, 1e-5);
    EXPECT_LT(*r.camera.position_sigma_m, 1e-6);
    ASSERT_EQ(r.residuals.size(), s.points.size());
    EXPECT_EQ(r.inliers, 12);
  }
}

// ---------------------------------------------------------------------------------------------
// Misclicked labels

TEST(CalibPose, MisclicksAreRejectedByName) {
  std::mt19937_64 rng(202);
  std::uniform_real_distribution<double> mag(25.0, 120.0), ang(0.0, 2 * CV_PI);
  std::vector<double> rot, pos, rot_ref, pos_ref;
  int false_rejections = 0;
  const int cases = 150;
  for (int c = 0; c < cases; ++c) {
    const Scene s = randomScene(rng);
    std::vector<Correspondence> pts = withNoise(s.points, rng, 1.0);
    const int bad = 2 + c % 2;  // 2 or 3 of 12: 20 % on average
    std::vector<int> order(pts.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    std::shuffle(order.begin(), order.end(), rng);
    std::set<std::string> misclicked;
    for (int b = 0; b < bad; ++b) {
      const double m = mag(rng), a = ang(rng);
      pts[order[b]].pixel += cv::Point2d(m * std::cos(a), m * std::sin(a));
      misclicked.insert(pts[order[b]].name);
    }
    const PoseResult r = solvePose(intrinsicsOf(s.truth), pts);
    ASSERT_EQ(r.status, PoseStatus::Solved) << "case " << c << ": " << r.message;
    const std::set<std::string> rejected(r.rejected.begin(), r.rejected.end());
    for (const auto& name : misclicked)
      EXPECT_TRUE(rejected.count(name)) << "case " << c << ": " << name << " kept; " << r.message;
    false_rejections += static_cast<int>(rejected.size()) - bad;
    for (const Residual& res : r.residuals)
      if (misclicked.count(res.name)) {
        EXPECT_FALSE(res.inlier);
        EXPECT_GT(res.px, 8.0);
        EXPECT_NE(r.message.find(res.name), std::string::npos);
      }
    rot.push_back(rotationErrorDeg(r.camera.rvec, s.truth.rvec));
    pos.push_back(positionError(r.camera, s.truth));

    // Reference: SQPnP + LM on the true inliers alone.
    std::vector<cv::Point3d> w;
    std::vector<cv::Point2d> p;
    for (const auto& q : pts)
      if (!misclicked.count(q.name)) w.push_back(q.world), p.push_back(q.pixel);
    cv::Mat rv, tv;
    ASSERT_TRUE(cv::solvePnP(w, p, s.truth.camera_matrix, s.truth.distortion, rv, tv, false, cv::SOLVEPNP_SQPNP));
    cv::solvePnPRefineLM(w, p, s.truth.camera_matrix, s.truth.distortion, rv, tv);
    Camera ref = s.truth;
    ref.rvec = cv::Vec3d(rv.ptr<double>());
    ref.tvec = cv::Vec3d(tv.ptr<double>());
    rot_ref.push_back(rotationErrorDeg(ref.rvec, s.truth.rvec));
    pos_ref.push_back(positionError(ref, s.truth));
  }
  std::printf(
      "20 %% misclicks, %d cases: median rotation error %.3f deg (true inliers only %.3f), position %.2f mm "
      "(%.2f mm); %d good points rejected\n",
      cases, median(rot), median(rot_ref), 1000 * median(pos), 1000 * median(pos_ref), false_rejections);
  EXPECT_LE(median(rot), 1.5 * median(rot_ref));
  EXPECT_LE(median(pos), 1.5 * median(pos_ref));
  EXPECT_LE(false_rejections, 3);
}

// ---------------------------------------------------------------------------------------------
// Honest sigmas

TEST(CalibPose, SigmasAreHonest) {
  std::mt19937_64 rng(303);
  const int cases = 250;
  int rot_ok = 0, pos_ok = 0, larger = 0;
  std::vector<double> ratio, rot_sigma;
  for (int c = 0; c < cases; ++c) {
    const Scene s = randomScene(rng);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<cv::Point2d> noise;
    for (std::size_t i = 0; i < s.points.size(); ++i) noise.emplace_back(g(rng), g(rng));
    auto noisy = [&](double sigma) {
      std::vector<Correspondence> pts = s.points;
      for (std::size_t i = 0; i < pts.size(); ++i) pts[i].pixel += sigma * noise[i];
      return pts;
    };
    const PoseResult r1 = solvePose(intrinsicsOf(s.truth), noisy(1.0));
    const PoseResult r3 = solvePose(intrinsicsOf(s.truth), noisy(3.0));
    ASSERT_EQ(r1.status, PoseStatus::Solved) << r1.message;
    ASSERT_EQ(r3.status, PoseStatus::Solved) << r3.message;
    rot_ok += rotationErrorDeg(r1.camera.rvec, s.truth.rvec) <= 3 * *r1.camera.rotation_sigma_deg;
    pos_ok += positionError(r1.camera, s.truth) <= 3 * *r1.camera.position_sigma_m;
    larger += *r3.camera.rotation_sigma_deg > *r1.camera.rotation_sigma_deg &&
              *r3.camera.position_sigma_m > *r1.camera.position_sigma_m;
    ratio.push_back(*r3.camera.rotation_sigma_deg / *r1.camera.rotation_sigma_deg);
    rot_sigma.push_back(*r1.camera.rotation_sigma_deg);
  }
  std::printf(
      "%d cases at 1 px: rotation error <= 3 sigma in %.1f %%, position in %.1f %%; median rotation sigma %.3f deg; "
      "3 px / 1 px sigma ratio median %.2f\n",
      cases, 100.0 * rot_ok / cases, 100.0 * pos_ok / cases, median(rot_sigma), median(ratio));
  EXPECT_GE(rot_ok, 0.9 * cases);
  EXPECT_GE(pos_ok, 0.9 * cases);
  EXPECT_EQ(larger, cases);
  EXPECT_GT(median(ratio), 2.5);
}

// ---------------------------------------------------------------------------------------------
// Degenerate input: a status and a message saying what to add, never a pose

TEST(CalibPose, TooFewPoints) {
  std::mt19937_64 rng(11);
  const Scene s = randomScene(rng, 5);
  for (int n : {0, 1, 3, 5}) {
    const std::vector<Correspondence> pts(s.points.begin(), s.points.begin() + n);
    const PoseResult r = solvePose(s.truth, pts);
    EXPECT_EQ(r.status, PoseStatus::TooFewPoints) << n;
    EXPECT_NE(r.message.find("at least 6"), std::string::npos) << r.message;
    EXPECT_TRUE(r.residuals.empty());
  }
  // Four exact points are enough when the caller asks for four.
  PoseOptions four;
  four.min_inliers = 4;
  const Scene t = randomScene(rng, 4);
  EXPECT_EQ(solvePose(t.truth, t.points, four).status, PoseStatus::Solved);
  EXPECT_EQ(solvePose(t.truth, {t.points.begin(), t.points.begin() + 3}, four).status, PoseStatus::TooFewPoints);
}

TEST(CalibPose, CollinearPoints) {
  std::mt19937_64 rng(12);
  const Camera cam = validCamera(rng);
  std::vector<cv::Point3d> world;
  for (int i = 0; i < 12; ++i) world.emplace_back(-0.5 + 0.09 * i, 0.2 - 0.03 * i + 1e-4 * (i % 2), 0.1 + 0.02 * i);
  const auto px = project(cam, world);
  std::vector<Correspondence> pts;
  for (int i = 0; i < 12; ++i) pts.push_back({"l" + std::to_string(i), px[i], world[i]});
  PoseResult r = solvePose(cam, pts);
  EXPECT_EQ(r.status, PoseStatus::Collinear);
  EXPECT_NE(r.message.find("line"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("add at least two points off that line"), std::string::npos) << r.message;

  // Nine points on the line and three off it, all three misclicked: whatever agrees is a line plus
  // at most one point, which would set the roll about the line unchecked.
  const std::vector<cv::Point3d> off = {{0.3, 0.3, -0.2}, {-0.3, -0.2, 0.3}, {0.1, -0.35, -0.3}};
  const auto off_px = project(cam, off);
  for (int i = 0; i < 3; ++i) pts[i] = {"off" + std::to_string(i), off_px[i] + cv::Point2d(60, -40 * i), off[i]};
  r = solvePose(cam, pts);
  EXPECT_TRUE(r.status == PoseStatus::Collinear || r.status == PoseStatus::TooFewInliers) << r.message;
  std::printf("line plus three misclicks off it: %s: %s\n", toString(r.status), r.message.c_str());
  // With two good points off the line it solves.
  pts[1].pixel = off_px[1];
  pts[2].pixel = off_px[2];
  r = solvePose(cam, pts);
  EXPECT_EQ(r.status, PoseStatus::Solved) << r.message;
  EXPECT_EQ(r.rejected, std::vector<std::string>{"off0"});
}

TEST(CalibPose, TinyPatchFarAwayIsPoorGeometry) {
  std::mt19937_64 rng(13);
  // A 6 cm cube 15 m in front of the camera: a few pixels across. Exact pixels still refuse.
  const Camera cam = lookAt(Vec3(15, 0, 0.5), Vec3(0, 0, 0.5), 320, 240, 290, {-0.1, 0.02, 0, 0, 0});
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  std::vector<Correspondence> pts;
  for (int i = 0; i < 12; ++i) {
    const cv::Point3d w(u(rng), u(rng), 0.5 + u(rng));
    pts.push_back({"t" + std::to_string(i), project(cam, {w})[0], w});
  }
  for (double noise : {0.0, 1.0}) {
    const PoseResult r = solvePose(cam, withNoise(pts, rng, noise));
    EXPECT_EQ(r.status, PoseStatus::PoorGeometry) << r.message;
    EXPECT_NE(r.message.find("spread wider"), std::string::npos) << r.message;
  }
  // A 40 cm planar patch at 12 m with 1 px noise: the tilt is not determined either.
  std::vector<Correspondence> wall;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const cv::Point3d w(3.0, -0.2 + 0.4 * i / 3, 0.3 + 0.4 * j / 3);
      wall.push_back({"w" + std::to_string(4 * i + j), project(cam, {w})[0], w});
    }
  const PoseResult r = solvePose(cam, withNoise(wall, rng, 1.0));
  EXPECT_EQ(r.status, PoseStatus::PoorGeometry) << r.message;
}

TEST(CalibPose, SmallPlanarPatchNeverGivesAConfidentWrongPose) {
  // A 20 cm planar grid at ~2.3 m (about 5 deg of view): its mirrored (Necker) pose fits nearly as
  // well, so it is refused; when it is solved, the pose is right within its sigmas.
  std::mt19937_64 rng(17);
  const Camera cam = lookAt(Vec3(2.0, 0.6, 1.3), Vec3(0, 0, 0.5), 640, 480, 600, {-0.1, 0.02, 0, 0, 0});
  std::vector<Correspondence> grid;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) {
      const cv::Point3d w(0, -0.1 + 0.1 * i, 0.4 + 0.2 * j / 3);
      grid.push_back({"g" + std::to_string(4 * i + j), project(cam, {w})[0], w});
    }
  int mirrored = 0;
  for (int c = 0; c < 40; ++c) {
    const PoseResult r = solvePose(cam, withNoise(grid, rng, 1.0));
    if (r.status == PoseStatus::Solved) {
      EXPECT_LE(rotationErrorDeg(r.camera.rvec, cam.rvec), 3 * *r.camera.rotation_sigma_deg) << r.message;
    } else {
      EXPECT_EQ(r.status, PoseStatus::PoorGeometry) << r.message;
      mirrored += r.message.find("mirrored pose") != std::string::npos;
    }
  }
  EXPECT_GE(mirrored, 20);
}

TEST(CalibPose, PointsSeenEdgeOnArePoorGeometry) {
  // A plane through the camera centre: all points on one image line.
  const Camera cam = lookAt(Vec3(2, 0, 1), Vec3(0, 0, 1), 320, 240, 290, {0, 0, 0, 0, 0});
  std::vector<Correspondence> pts;
  for (int i = 0; i < 12; ++i) {
    const cv::Point3d w(-0.3 * (i % 4), -0.5 + 0.09 * i, 1.0);
    pts.push_back({"e" + std::to_string(i), project(cam, {w})[0], w});
  }
  const PoseResult r = solvePose(cam, pts);
  EXPECT_EQ(r.status, PoseStatus::PoorGeometry) << r.message;
  EXPECT_NE(r.message.find("one line in the image"), std::string::npos) << r.message;
}

TEST(CalibPose, TooFewInliers) {
  std::mt19937_64 rng(14);
  const Scene s = randomScene(rng);
  std::vector<Correspondence> pts = withNoise(s.points, rng, 1.0);
  std::uniform_real_distribution<double> u(0, 300);
  for (int i = 0; i < 8; ++i) pts[i].pixel = cv::Point2d(u(rng), u(rng) * 0.8);
  const PoseResult r = solvePose(s.truth, pts);
  EXPECT_EQ(r.status, PoseStatus::TooFewInliers) << r.message;
  EXPECT_NE(r.message.find("only"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("check the labels"), std::string::npos) << r.message;
  ASSERT_EQ(r.residuals.size(), pts.size());
  EXPECT_GE(r.rejected.size(), 6u);
}

TEST(CalibPose, TagsOnAWallSolve) {
  // Four 16 cm tags on the wall x = 0, seen from 2.5 m at an angle: 16 coplanar corners.
  std::mt19937_64 rng(15);
  const Camera cam = lookAt(Vec3(2.2, 1.0, 1.4), Vec3(0, 0.1, 1.0), 640, 480, 600, {-0.12, 0.03, 0.001, -0.001, 0});
  std::vector<Correspondence> pts;
  const double centres[4][2] = {{-0.5, 0.6}, {0.6, 0.6}, {-0.5, 1.5}, {0.6, 1.5}};
  for (int t = 0; t < 4; ++t)
    for (int k = 0; k < 4; ++k) {
      const double dy = (k == 1 || k == 2) ? 0.08 : -0.08, dz = k >= 2 ? 0.08 : -0.08;
      const cv::Point3d w(0.0, centres[t][0] + dy, centres[t][1] + dz);
      pts.push_back({"tag" + std::to_string(t) + "." + std::to_string(k), project(cam, {w})[0], w});
    }
  std::vector<double> rot;
  for (int c = 0; c < 20; ++c) {
    const PoseResult r = solvePose(cam, withNoise(pts, rng, 1.0));
    ASSERT_EQ(r.status, PoseStatus::Solved) << r.message;
    rot.push_back(rotationErrorDeg(r.camera.rvec, cam.rvec));
    EXPECT_LT(positionError(r.camera, cam), 0.05);
  }
  EXPECT_LT(median(rot), 0.5);
}

// ---------------------------------------------------------------------------------------------
// Unusable input

TEST(CalibPose, BadInputThrows) {
  std::mt19937_64 rng(16);
  const Scene s = randomScene(rng);
  auto pts = s.points;
  pts[3].pixel.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(solvePose(s.truth, pts), InputError);
  pts = s.points;
  pts[2].world.z = std::numeric_limits<double>::infinity();
  EXPECT_THROW(solvePose(s.truth, pts), InputError);
  pts = s.points;
  pts[5].name = pts[1].name;
  try {
    solvePose(s.truth, pts);
    ADD_FAILURE() << "no error for a repeated name";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'p1' given twice"), std::string::npos) << e.what();
  }
  pts = s.points;
  pts[0].name.clear();
  EXPECT_THROW(solvePose(s.truth, pts), InputError);
  PoseOptions bad;
  bad.min_inliers = 3;
  EXPECT_THROW(solvePose(s.truth, s.points, bad), InputError);
  bad = {};
  bad.ransac_threshold_px = std::nan("");
  EXPECT_THROW(solvePose(s.truth, s.points, bad), InputError);
  Camera no_focal = s.truth;
  no_focal.camera_matrix(0, 0) = 0;
  EXPECT_THROW(solvePose(no_focal, s.points), CameraError);
}

// How far apart two poses are: a known turn about the camera centre and a known shift, down to
// angles where the trace alone loses its digits; the centre is -R^T t.
TEST(CalibPose, PoseDifferenceOfAKnownTurnAndShift) {
  const Camera a = lookAt(Vec3(2.0, -1.5, 1.3), Vec3(0.3, 0.1, 0.5), 1280, 720, 1000, {});
  const cv::Vec3d centre = cameraCentre(a);
  EXPECT_LT(cv::norm(centre - cv::Vec3d(2.0, -1.5, 1.3)), 1e-12);
  for (double angle_deg : {0.0, 1e-7, 0.5, 30.0, 179.0}) {
    cv::Matx33d ra, turn;
    cv::Rodrigues(a.rvec, ra);
    cv::Rodrigues(cv::Vec3d(0.6, 0.0, 0.8) * (angle_deg * CV_PI / 180.0), turn);
    Camera b = a;
    const cv::Matx33d rb = turn * ra;
    cv::Rodrigues(rb, b.rvec);
    const cv::Vec3d moved = centre + cv::Vec3d(0.006, -0.008, 0.0);
    b.tvec = -(rb * moved);
    const PoseDifference d = poseDifference(a, b);
    EXPECT_NEAR(d.rotation_deg, angle_deg, 1e-9 + 1e-9 * angle_deg) << angle_deg;
    EXPECT_NEAR(d.position_m, 0.01, 1e-12) << angle_deg;
    EXPECT_NEAR(poseDifference(b, a).rotation_deg, angle_deg, 1e-9 + 1e-9 * angle_deg) << angle_deg;
  }
  EXPECT_EQ(poseDifference(a, a).rotation_deg, 0.0);
  EXPECT_EQ(poseDifference(a, a).position_m, 0.0);
}

}  // namespace
