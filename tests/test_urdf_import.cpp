// URDF/SRDF import of the test robot and its errors.
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "kccd/checker.hpp"
#include "kccd/input_error.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "support/files.hpp"
#include "support/reference_distance.hpp"

namespace km = kccd::modelling;
using kccd::Model;
using kccd::Vec3;

TEST(UrdfImport, TestRobot) {
  const std::string dir = std::string(KCCD_TEST_DATA_DIR) + "/urdf";
  km::ImportOptions opt;
  opt.srdf = dir + "/two_link.srdf";
  opt.fit.points = 4;
  opt.packages["kccd_test"] = dir;
  const std::string text = km::importUrdf(dir + "/two_link.urdf", opt);
  const Model m = kccd::parseModel(text, "imported");
  EXPECT_EQ(m.name, "two_link");
  ASSERT_EQ(m.joints.size(), 4u);
  const kccd::Joint& yaw = m.joints[m.jointIndex("yaw")];
  EXPECT_EQ(yaw.type, kccd::JointType::Revolute);
  EXPECT_EQ(yaw.parent, kccd::kWorld);
  ASSERT_TRUE(yaw.limits);
  EXPECT_DOUBLE_EQ((*yaw.limits)[0], -2.0);
  EXPECT_NEAR((yaw.origin.translation() - Vec3(0, 0, 0.1)).norm(), 0, 1e-12);
  EXPECT_NEAR((yaw.origin.linear() - Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix()).norm(), 0, 1e-9);
  const kccd::Joint& lift = m.joints[m.jointIndex("lift")];
  EXPECT_EQ(lift.type, kccd::JointType::Prismatic);
  EXPECT_EQ(lift.parent, m.jointIndex("yaw"));
  const kccd::Joint& spin = m.joints[m.jointIndex("spin")];
  EXPECT_EQ(spin.type, kccd::JointType::Revolute);  // continuous: no limits
  EXPECT_FALSE(spin.limits);
  EXPECT_NEAR((spin.axis - Vec3::UnitX()).norm(), 0, 1e-12);
  EXPECT_EQ(m.joints[m.jointIndex("tip")].type, kccd::JointType::Fixed);
  ASSERT_EQ(m.bodies.size(), 4u);  // `marker` has no collision geometry
  EXPECT_EQ(m.bodies[m.bodyIndex("base")].frame, kccd::kWorld);
  EXPECT_EQ(m.bodies[m.bodyIndex("tool")].frame, m.jointIndex("spin"));
  EXPECT_EQ(m.stateSize(), 3);

  // The fitted bodies contain the true collision geometry (in each link's frame).
  auto contains = [&](const std::string& body, const std::vector<Vec3>& pts) {
    const kccd::Body& b = m.bodies[m.bodyIndex(body)];
    for (const Vec3& p : pts)
      EXPECT_LE(static_cast<double>(kccd::testing::referencePointHullDistance(p, b.points)), b.radius)
          << body << " misses " << p.transpose();
  };
  std::vector<Vec3> box;
  for (int i = 0; i < 8; ++i) box.emplace_back(i & 1 ? 0.2 : -0.2, i & 2 ? 0.15 : -0.15, i & 4 ? 0.1 : 0.0);
  contains("base", box);
  std::vector<Vec3> rim;
  for (int i = 0; i < 360; ++i) {
    const double a = i * std::numbers::pi / 180;
    rim.emplace_back(0.05 * std::cos(a), 0.05 * std::sin(a), i % 2 ? 0.5 : 0.0);
  }
  contains("column", rim);
  // Slider: the sphere, and the STL bar (scaled by 0.5, rotated by pitch 90 degrees).
  std::vector<Vec3> slider{Vec3(0.14, 0, 0), Vec3(0.06, 0, 0), Vec3(0.1, 0.04, 0), Vec3(0.1, 0, -0.04)};
  const Eigen::Matrix3d pitch = Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitY()).toRotationMatrix();
  for (const Vec3& v : {Vec3(-0.1, -0.02, 0), Vec3(0.1, 0.02, 0), Vec3(0, 0, 0.2)}) slider.push_back(pitch * (0.5 * v));
  contains("slider", slider);
  // Tool: the cone from package://, turned from +y to -x: apex at the origin, base rim at x = 0.1.
  std::vector<Vec3> cone{Vec3(0, 0, 0)};
  for (int i = 0; i < 360; ++i) {
    const double a = i * std::numbers::pi / 180;
    cone.emplace_back(0.1, 0.03 * std::cos(a), 0.03 * std::sin(a));
  }
  contains("tool", cone);

  // SRDF: adjacent pairs ignored; a pair naming a link without geometry dropped.
  const std::string ignore = text.substr(text.find("ignore:"));
  EXPECT_NE(ignore.find("[base, column, srdf]"), std::string::npos);  // the SRDF's word is kept
  EXPECT_NE(ignore.find("[slider, tool, srdf]"), std::string::npos);
  EXPECT_NE(ignore.find("[column, slider, adjacent]"), std::string::npos);  // and the rule adds this one
  EXPECT_EQ(ignore.find("marker"), std::string::npos);
  EXPECT_EQ(m.pairs.size(), 3u);
  opt.keep_adjacent = true;  // then only the SRDF's pairs are ignored
  const std::string kept = km::importUrdf(dir + "/two_link.urdf", opt);
  EXPECT_NE(kept.find("[base, column, srdf]"), std::string::npos) << kept;
  EXPECT_NE(kept.find("[slider, tool, srdf]"), std::string::npos) << kept;
  EXPECT_EQ(kccd::parseModel(kept, "kept").pairs.size(), 4u);
}

TEST(UrdfImport, ClearErrors) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kccd_test_urdf";
  std::filesystem::create_directories(dir);
  auto message = [](const std::string& path, const km::ImportOptions& o = {}) {
    try {
      km::importUrdf(path, o);
    } catch (const kccd::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string link =
      "<link name=\"a\"><collision><geometry><sphere radius=\"0.1\"/></geometry></collision></link>";
  std::ofstream(dir / "broken.urdf") << "<robot name=\"r\">\n<link name=\"a\">\n</robot>\n";
  EXPECT_NE(message((dir / "broken.urdf").string()).find("broken.urdf:"), std::string::npos);
  std::ofstream(dir / "package.urdf")
      << "<robot name=\"r\"><link name=\"a\"><collision><geometry>"
         "<mesh filename=\"package://nowhere/m.stl\"/></geometry></collision></link></robot>";
  EXPECT_NE(
      message((dir / "package.urdf").string()).find("unknown package 'nowhere' (give --package-path nowhere=DIR)"),
      std::string::npos);
  EXPECT_NE(message((dir / "missing.urdf").string()).find("cannot open"), std::string::npos);
  // A mesh that is not there: the message starts with the URDF and names the link and the mesh.
  std::ofstream(dir / "mesh.urdf") << "<robot name=\"r\"><link name=\"a\"><collision><geometry>"
                                      "<mesh filename=\"meshes/none.stl\"/></geometry></collision></link></robot>";
  const std::string missing_mesh = message((dir / "mesh.urdf").string());
  EXPECT_EQ(missing_mesh.rfind((dir / "mesh.urdf").string() + ": link a: ", 0), 0u) << missing_mesh;
  EXPECT_NE(missing_mesh.find("none.stl: cannot open the file"), std::string::npos) << missing_mesh;
  // A moving joint with a zero axis (found by fuzz_urdf), and a model the loader refuses (a link
  // beyond the 1e6 m bound): both start with the URDF's name.
  const std::string two_links =
      "<link name=\"b\"><collision><geometry><sphere radius=\"0.1\"/></geometry></collision></link>";
  std::ofstream(dir / "axis.urdf") << "<robot name=\"r\">" << link << two_links
                                   << "<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/>"
                                      "<axis xyz=\"0 0 0\"/></joint></robot>";
  const std::string zero = message((dir / "axis.urdf").string());
  EXPECT_EQ(zero.rfind((dir / "axis.urdf").string() + ":1: joint 'j': axis xyz: zero axis", 0), 0u) << zero;
  std::ofstream(dir / "far.urdf") << "<robot name=\"r\">" << link << two_links
                                  << "<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/>"
                                     "<origin xyz=\"2e6 0 0\"/></joint></robot>";
  const std::string far = message((dir / "far.urdf").string());
  EXPECT_EQ(far.rfind((dir / "far.urdf").string() + ": the imported model does not load: ", 0), 0u) << far;
}

// Mobile bases: a planar joint becomes prismatic x, prismatic y and revolute yaw in its plane, a
// floating joint translation3d then rotation3d; the child link moves with the last of them, and
// the chain places it as the URDF joint would.
TEST(UrdfImport, MobileBasesBecomeJointChains) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kccd_test_urdf";
  std::filesystem::create_directories(dir);
  const std::string box = "<collision><geometry><box size=\"0.2 0.2 0.2\"/></geometry></collision>";
  std::ofstream(dir / "mobile.urdf")
      << "<robot name=\"mobile\"><link name=\"floor\">" << box << "</link>"
      << "<link name=\"cart\">" << box << "</link><link name=\"drone\">" << box << "</link>"
      << "<link name=\"slider\">" << box << "</link>"
      << "<joint name=\"base\" type=\"planar\"><parent link=\"floor\"/><child link=\"cart\"/>"
         "<origin xyz=\"1 0 0.1\" rpy=\"0 0 0.3\"/><axis xyz=\"0 0 1\"/></joint>"
      << "<joint name=\"fly\" type=\"floating\"><parent link=\"floor\"/><child link=\"drone\"/>"
         "<origin xyz=\"0 2 1\"/></joint>"
      << "<joint name=\"wall\" type=\"planar\"><parent link=\"cart\"/><child link=\"slider\"/>"
         "<axis xyz=\"2 0 0\"/></joint></robot>";
  km::ImportOptions opt;
  opt.fit.points = 4;
  const Model m = kccd::parseModel(km::importUrdf((dir / "mobile.urdf").string(), opt), "imported");
  ASSERT_EQ(m.joints.size(), 8u);
  const kccd::Joint& x = m.joints[m.jointIndex("base_x")];
  const kccd::Joint& y = m.joints[m.jointIndex("base_y")];
  const kccd::Joint& yaw = m.joints[m.jointIndex("base_yaw")];
  EXPECT_EQ(x.type, kccd::JointType::Prismatic);
  EXPECT_EQ(y.type, kccd::JointType::Prismatic);
  EXPECT_EQ(yaw.type, kccd::JointType::Revolute);
  EXPECT_EQ(y.parent, m.jointIndex("base_x"));
  EXPECT_EQ(yaw.parent, m.jointIndex("base_y"));
  EXPECT_FALSE(yaw.limits);
  EXPECT_EQ(m.bodies[m.bodyIndex("cart")].frame, m.jointIndex("base_yaw"));
  EXPECT_EQ(m.joints[m.jointIndex("fly")].type, kccd::JointType::Translation3d);
  EXPECT_EQ(m.joints[m.jointIndex("fly_rotation")].type, kccd::JointType::Rotation3d);
  EXPECT_EQ(m.bodies[m.bodyIndex("drone")].frame, m.jointIndex("fly_rotation"));
  // The tilted plane: two orthonormal axes normal to (1, 0, 0), the yaw about it.
  const kccd::Joint& wx = m.joints[m.jointIndex("wall_x")];
  const kccd::Joint& wy = m.joints[m.jointIndex("wall_y")];
  const kccd::Joint& wyaw = m.joints[m.jointIndex("wall_yaw")];
  EXPECT_NEAR(wx.axis.dot(Vec3::UnitX()), 0.0, 1e-12);
  EXPECT_NEAR(wy.axis.dot(Vec3::UnitX()), 0.0, 1e-12);
  EXPECT_NEAR(wx.axis.dot(wy.axis), 0.0, 1e-12);
  EXPECT_NEAR((wyaw.axis - Vec3::UnitX()).norm(), 0.0, 1e-12);
  EXPECT_EQ(wx.parent, m.jointIndex("base_yaw"));
  // Placement: the cart at planar state (x, y, yaw) sits at origin * (x, y, 0) * Rz(yaw), the
  // drone at its position and rotation vector.
  std::vector<double> q(static_cast<std::size_t>(m.stateSize()), 0.0);
  q[static_cast<std::size_t>(x.state_offset)] = 0.3;
  q[static_cast<std::size_t>(y.state_offset)] = -0.2;
  q[static_cast<std::size_t>(yaw.state_offset)] = 0.5;
  const kccd::Joint& fly = m.joints[m.jointIndex("fly")];
  const kccd::Joint& fly_rot = m.joints[m.jointIndex("fly_rotation")];
  for (int k = 0; k < 3; ++k) q[static_cast<std::size_t>(fly.state_offset + k)] = 0.1 * (k + 1);
  q[static_cast<std::size_t>(fly_rot.state_offset + 2)] = 0.7;
  std::vector<kccd::Pose> poses(m.joints.size());
  ASSERT_TRUE(kccd::framePoses(m, q, poses));
  kccd::Pose expected = kccd::Pose::Identity();
  expected.translation() = Vec3(1, 0, 0.1);
  expected.linear() = Eigen::AngleAxisd(0.3, Vec3::UnitZ()).toRotationMatrix();
  expected = expected * Eigen::Translation3d(0.3, -0.2, 0) * Eigen::AngleAxisd(0.5, Vec3::UnitZ());
  EXPECT_NEAR((kccd::framePose(poses, m.jointIndex("base_yaw")).matrix() - expected.matrix()).norm(), 0, 1e-12);
  kccd::Pose drone = kccd::Pose::Identity();
  drone.translation() = Vec3(0.1, 2.2, 1.3);
  drone.linear() = Eigen::AngleAxisd(0.7, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_NEAR((kccd::framePose(poses, m.jointIndex("fly_rotation")).matrix() - drone.matrix()).norm(), 0, 1e-12);
  // A chain name taken by another URDF joint is an error, not a silent rename.
  std::ofstream(dir / "clash.urdf")
      << "<robot name=\"r\"><link name=\"a\">" << box << "</link><link name=\"b\"/><link name=\"c\"/>"
      << "<joint name=\"base\" type=\"planar\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/></joint>"
      << "<joint name=\"base_yaw\" type=\"fixed\"><parent link=\"a\"/><child link=\"c\"/></joint></robot>";
  try {
    km::importUrdf((dir / "clash.urdf").string(), opt);
    ADD_FAILURE() << "no error";
  } catch (const kccd::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("base_yaw would repeat a joint name"), std::string::npos) << e.what();
  }
}

// --hulls: each body is its link's convex hull (the box's 8 corners, radius 0), the reference
// bench_fit measures a fit's looseness against; a fitted body contains it.
TEST(UrdfImport, HullBodiesAreTheLinksConvexHulls) {
  const std::string dir = std::string(KCCD_TEST_DATA_DIR) + "/urdf";
  km::ImportOptions opt;
  opt.packages["kccd_test"] = dir;
  opt.fit.method = km::FitMethod::Hull;
  const Model hull = kccd::parseModel(km::importUrdf(dir + "/two_link.urdf", opt), "hull");
  const kccd::Body& base = hull.bodies[hull.bodyIndex("base")];
  ASSERT_EQ(base.points.size(), 8u);
  EXPECT_LT(base.radius, 1e-14);  // a few ulps: rounding of the printed points and of the distances
  for (const Vec3& p : base.points) {
    EXPECT_NEAR(std::abs(p.x()), 0.2, 1e-12);
    EXPECT_NEAR(std::abs(p.y()), 0.15, 1e-12);
    EXPECT_TRUE(std::abs(p.z()) < 1e-12 || std::abs(p.z() - 0.1) < 1e-12) << p.transpose();
  }
  // The slider's URDF sphere (radius 0.04 at x = 0.1) is inside its hull body.
  const kccd::Body& slider = hull.bodies[hull.bodyIndex("slider")];
  for (const Vec3& d : std::vector<Vec3>{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ(), Vec3(1, 1, 1).normalized(),
                                         Vec3(1, -2, 3).normalized()})
    for (double sign : {1.0, -1.0})
      EXPECT_LE(static_cast<double>(
                    kccd::testing::referencePointHullDistance(Vec3(0.1, 0, 0) + sign * 0.04 * d, slider.points)),
                slider.radius + 1e-12)
          << d.transpose();
  opt.fit.method = km::FitMethod::Tolerance;
  opt.fit.points = 4;
  const Model fitted = kccd::parseModel(km::importUrdf(dir + "/two_link.urdf", opt), "fitted");
  for (const kccd::Body& b : hull.bodies) {
    if (b.name == "slider") continue;  // its sphere is a circumscribed polytope there, an exact ball in the fit
    const kccd::Body& f = fitted.bodies[fitted.bodyIndex(b.name)];
    for (const Vec3& p : b.points)
      EXPECT_LE(static_cast<double>(kccd::testing::referencePointHullDistance(p, f.points)), f.radius + 1e-9)
          << b.name << " " << p.transpose();
  }
}

namespace {

// An ASCII STL of boxes (12 triangles each), each box [lo, hi].
std::string boxesStl(const std::vector<std::array<Vec3, 2>>& boxes) {
  std::ostringstream out;
  out.precision(17);
  out << "solid boxes\n";
  static constexpr int kFaces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& box : boxes) {
    const Vec3& lo = box[0];
    const Vec3& hi = box[1];
    auto corner = [&](int i) {
      return Vec3(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    };
    for (const auto& f : kFaces)
      for (const std::array<int, 3> t : {std::array<int, 3>{f[0], f[1], f[2]}, std::array<int, 3>{f[0], f[2], f[3]}}) {
        out << "facet normal 0 0 0\nouter loop\n";
        for (int i : t) out << "vertex " << corner(i).x() << " " << corner(i).y() << " " << corner(i).z() << "\n";
        out << "endloop\nendfacet\n";
      }
  }
  return out.str() + "endsolid boxes\n";
}

}  // namespace

// A forearm ending in a fork around a wrist (the KR5's shape): the default import splits the
// forearm into pieces (bodies forearm/1, ... with link: forearm, each within the tolerance of its
// piece's hull), which leave the wrist in the gap clear of a 1 mm margin where the forearm's one
// hull holds it (the gap leaves 15 mm each side; a piece may keep up to the 10 mm concavity); the pieces hold every
// vertex of the mesh, and the point budget holds every body.
TEST(UrdfImport, ConcaveLinkInPiecesClearsWhatItsHullHolds) {
  const std::string tag = "kccd_import_pieces";
  kccd::testing::writeScratch(tag, "forearm.stl",
                              boxesStl({{Vec3(0.0, -0.06, -0.04), Vec3(0.2, 0.06, 0.04)},
                                        {Vec3(0.19, -0.06, -0.04), Vec3(0.32, -0.03, 0.04)},
                                        {Vec3(0.19, 0.03, -0.04), Vec3(0.32, 0.06, 0.04)}}));
  kccd::testing::writeScratch(tag, "wrist.stl", boxesStl({{Vec3(-0.02, -0.015, -0.02), Vec3(0.02, 0.015, 0.02)}}));
  const std::string urdf = kccd::testing::writeScratch(tag, "fork.urdf", R"(<?xml version="1.0"?>
<robot name="fork">
  <link name="base"/>
  <link name="forearm"><collision><geometry><mesh filename="forearm.stl"/></geometry></collision></link>
  <link name="wrist"><collision><geometry><mesh filename="wrist.stl"/></geometry></collision></link>
  <link name="tip"/>
  <joint name="elbow" type="revolute"><parent link="base"/><child link="forearm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="pitch" type="revolute"><parent link="forearm"/><child link="tip"/><origin xyz="0.26 0 0"/>
    <axis xyz="0 1 0"/><limit lower="-0.5" upper="0.5" effort="1" velocity="1"/></joint>
  <joint name="roll" type="revolute"><parent link="tip"/><child link="wrist"/>
    <axis xyz="1 0 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
)");
  km::ImportOptions opt;
  opt.safety_margin = 0.001;
  opt.visuals = false;
  opt.fit.concavity = 0.01;
  const std::string text = km::importUrdf(urdf, opt);
  const Model m = kccd::parseModel(text, "fork (imported)");
  std::vector<int> pieces;
  for (std::size_t i = 0; i < m.bodies.size(); ++i)
    if (m.bodies[i].link == "forearm") pieces.push_back(static_cast<int>(i));
  ASSERT_GE(pieces.size(), 2u) << text;
  std::size_t most = 0;
  for (const kccd::Body& b : m.bodies) {
    EXPECT_GE(b.tolerance, 0.0) << b.name;
    EXPECT_LE(b.tolerance, opt.fit.tolerance) << b.name;
    most = std::max(most, b.points.size());
  }
  EXPECT_GE(static_cast<std::size_t>(m.point_budget), most);
  EXPECT_EQ(m.bodies[pieces[0]].name, "forearm/1");
  // The wrist is clear of every piece at the zero state, and (the pitch joint turns it) in a
  // band of states; the forearm's one hull holds it.
  opt.fit.max_pieces = 1;
  const Model whole = kccd::parseModel(km::importUrdf(urdf, opt), "fork (whole)");
  ASSERT_EQ(whole.bodies.size(), 2u);
  kccd::Checker in_pieces(m), in_one(whole);
  const kccd::QueryOptions q{.type = kccd::QueryType::Distances};
  for (const double pitch : {0.0, 0.2, -0.2}) {
    const std::vector<double> s{0.3, pitch, 1.0};
    EXPECT_GT(in_pieces.query(s, s, q).min_distance, opt.safety_margin) << pitch;
    EXPECT_EQ(in_one.query(s, s, q).min_distance, 0.0) << pitch;
  }
  // Every vertex of the forearm mesh lies inside one of its pieces.
  for (const double x : {0.0, 0.19, 0.2, 0.32})
    for (const double y : {-0.06, -0.03, 0.03, 0.06})
      for (const double z : {-0.04, 0.04}) {
        const Vec3 v(x, y, z);
        if (x > 0.2 && std::abs(y) < 0.03) continue;  // the gap
        double best = INFINITY;
        for (int i : pieces)
          best = std::min(best, static_cast<double>(kccd::testing::referencePointHullDistance(v, m.bodies[i].points)) -
                                    m.bodies[i].radius);
        EXPECT_LE(best, 0.0) << v.transpose();
      }
}
