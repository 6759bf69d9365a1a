// `kccd pairs` proofs against dense sampling with independent kinematics and distances, URDF
// import of a test robot, and in-place model edits.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "kccd/model.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "kccd/modelling/yaml_edit.hpp"
#include "support/random_model.hpp"
#include "support/reference_distance.hpp"

namespace km = kccd::modelling;
using kccd::Model;
using kccd::Vec3;

namespace {

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

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

TEST(UrdfImport, TestRobot) {
  const std::string dir = std::string(KCCD_TEST_DATA_DIR) + "/urdf";
  km::ImportOptions opt;
  opt.srdf = dir + "/two_link.srdf";
  opt.points = 4;
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
  EXPECT_NE(ignore.find("[base, column]"), std::string::npos);
  EXPECT_NE(ignore.find("[slider, tool]"), std::string::npos);
  EXPECT_EQ(ignore.find("marker"), std::string::npos);
  EXPECT_EQ(m.pairs.size(), 4u);
}

TEST(UrdfImport, ClearErrors) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kccd_test_urdf";
  std::filesystem::create_directories(dir);
  auto message = [](const std::string& path, const km::ImportOptions& o = {}) {
    try {
      km::importUrdf(path, o);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string link = "<link name=\"a\"><collision><geometry><sphere radius=\"0.1\"/></geometry></collision></link>";
  std::ofstream(dir / "floating.urdf") << "<robot name=\"r\">" << link
                                       << "<link name=\"b\"/><joint name=\"free\" type=\"floating\"><parent link=\"a\"/>"
                                          "<child link=\"b\"/></joint></robot>";
  EXPECT_NE(message((dir / "floating.urdf").string()).find("joint free is floating: not supported"), std::string::npos);
  std::ofstream(dir / "planar.urdf") << "<robot name=\"r\">" << link
                                     << "<link name=\"b\"/><joint name=\"slide\" type=\"planar\"><parent link=\"a\"/>"
                                        "<child link=\"b\"/><axis xyz=\"0 0 1\"/></joint></robot>";
  EXPECT_NE(message((dir / "planar.urdf").string()).find("planar"), std::string::npos);
  std::ofstream(dir / "broken.urdf") << "<robot name=\"r\">\n<link name=\"a\">\n</robot>\n";
  EXPECT_NE(message((dir / "broken.urdf").string()).find("broken.urdf:"), std::string::npos);
  std::ofstream(dir / "package.urdf") << "<robot name=\"r\"><link name=\"a\"><collision><geometry>"
                                         "<mesh filename=\"package://nowhere/m.stl\"/></geometry></collision></link></robot>";
  EXPECT_NE(message((dir / "package.urdf").string()).find("unknown package 'nowhere' (give --package-path nowhere=DIR)"),
            std::string::npos);
  EXPECT_NE(message((dir / "missing.urdf").string()).find("cannot open"), std::string::npos);
}

TEST(YamlEdit, BodyGeometryKeepsEverythingElse) {
  const std::string text = readFile(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
  const std::string edited =
      km::withBodyGeometry(text, "demo_arm.yaml", "forearm", "[[0, 0, 0], [0.1, 0.2, 0.3]]", "0.0625");
  const Model m = kccd::parseModel(edited, "edited");
  const kccd::Body& b = m.bodies[m.bodyIndex("forearm")];
  ASSERT_EQ(b.points.size(), 2u);
  EXPECT_EQ(b.points[1], Vec3(0.1, 0.2, 0.3));
  EXPECT_EQ(b.radius, 0.0625);
  // Every comment line survives, and the other bodies are unchanged.
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.find('#') != std::string::npos && line.find("forearm") == std::string::npos) {
      EXPECT_NE(edited.find(line.substr(line.find('#'))), std::string::npos) << line;
    }
  }
  const Model before = kccd::parseModel(text, "original");
  for (const kccd::Body& o : before.bodies) {
    if (o.name == "forearm") continue;
    EXPECT_EQ(o.points, m.bodies[m.bodyIndex(o.name)].points);
    EXPECT_EQ(o.radius, m.bodies[m.bodyIndex(o.name)].radius);
  }
  EXPECT_THROW(km::withBodyGeometry(text, "demo_arm.yaml", "nobody", "[[0, 0, 0]]", "0.1"), std::runtime_error);
  EXPECT_THROW(km::withBodyGeometry(text, "demo_arm.yaml", "forearm", "[]", "0.1"), std::runtime_error);
}

TEST(YamlEdit, BlockAndFlowStyles) {
  const std::string block =
      "kccd: 1\nname: t\njoints:\n  - {name: j, parent: world, type: revolute, axis: [0, 0, 1]}\nbodies:\n"
      "  - name: a   # the base\n    frame: world\n    points:\n      - [0, 0, 0]\n      - [1, 0, 0]\n"
      "    radius: 0.1  # metres\n  - {name: b, frame: j, points: [[0, 0, 2]], radius: 0.2}\n";
  std::string edited = km::withBodyGeometry(block, "block", "a", "[[5, 5, 5]]", "0.5");
  Model m = kccd::parseModel(edited, "edited");
  EXPECT_EQ(m.bodies[0].points.size(), 1u);
  EXPECT_EQ(m.bodies[0].radius, 0.5);
  EXPECT_NE(edited.find("# metres"), std::string::npos);
  EXPECT_NE(edited.find("# the base"), std::string::npos);
  edited = km::withBodyGeometry(edited, "block", "b", "[[1, 1, 1], [2, 2, 2]]", "0.25");
  m = kccd::parseModel(edited, "edited");
  EXPECT_EQ(m.bodies[1].points.size(), 2u);
  EXPECT_EQ(m.bodies[1].radius, 0.25);

  // ignore lists: added to a file without a pairs section, replaced in one with it.
  edited = km::withIgnoreList(edited, "block", {{{"a", "b"}}});
  m = kccd::parseModel(edited, "edited");
  EXPECT_TRUE(m.pairs.empty());
  edited = km::withIgnoreList(edited, "block", {});
  EXPECT_EQ(kccd::parseModel(edited, "edited").pairs.size(), 1u);
  const std::string flow = block + "pairs: {check: all}\n";
  EXPECT_TRUE(kccd::parseModel(km::withIgnoreList(flow, "flow", {{{"b", "a"}}}), "f").pairs.empty());
  const std::string nested = block + "pairs:\n  check: all   # every pair\n";
  const std::string with = km::withIgnoreList(nested, "nested", {{{"a", "b"}}});
  EXPECT_TRUE(kccd::parseModel(with, "n").pairs.empty());
  EXPECT_NE(with.find("# every pair"), std::string::npos);
  EXPECT_THROW(km::withIgnoreList(block, "block", {{{"a", "nobody"}}}), std::runtime_error);
}
