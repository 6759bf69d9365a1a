// Model files: what loads, and one clear message (file, line, field) for each kind of mistake.
#include <gtest/gtest.h>

#include <cmath>

#include <string>

#include "kccd/model.hpp"

namespace kccd {
namespace {

const std::string kGood = R"(kccd: 1
name: t
safety_margin: 0.01
joints:
  - name: base
    parent: world
    type: revolute
    origin: {xyz: [0, 0, 0.5], rpy: [0, 0, 1.5707963267948966]}
    axis: [0, 0, 2]
    sweep: fast
    limits: [-1, 1]
  - name: slide
    parent: base
    type: prismatic
    axis: [1, 0, 0]
  - name: pose
    parent: world
    type: translation3d
    error: 0.01
  - name: turn
    parent: pose
    type: rotation3d
    error: 0.02
bodies:
  - name: floor
    frame: world
    points: [[0, 0, 0]]
    radius: 0.1
  - name: arm
    frame: base
    points: [[0, 0, 0], [1, 0, 0]]
    radius: 0.05
  - name: tool
    frame: slide
    points: [[0, 0, 0]]
    radius: 0.02
  - name: box
    frame: turn
    points: [[0, 0, 0], [0.1, 0, 0]]
    radius: 0.03
pairs:
  ignore: [[arm, tool]]
)";

// Replaces the first occurrence of `from` in the good model.
std::string edit(const std::string& from, const std::string& to) {
  std::string s = kGood;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return s.replace(at, from.size(), to);
}

std::string loadError(const std::string& text) {
  try {
    parseModel(text, "cell.yaml");
  } catch (const ModelError& e) {
    return e.what();
  }
  return "(loaded)";
}

TEST(Model, LoadsAValidFile) {
  const Model m = parseModel(kGood, "cell.yaml");
  EXPECT_EQ(m.name, "t");
  EXPECT_DOUBLE_EQ(m.safety_margin, 0.01);
  ASSERT_EQ(m.joints.size(), 4u);
  EXPECT_EQ(m.stateSize(), 1 + 1 + 3 + 3);
  const std::vector<std::string> names{"base", "slide", "pose.x", "pose.y", "pose.z", "turn.x", "turn.y", "turn.z"};
  EXPECT_EQ(m.stateNames(), names);
  EXPECT_TRUE(m.joints[0].axis.isApprox(Vec3::UnitZ()));  // normalised on load
  EXPECT_EQ(m.joints[0].sweep, SweepMode::Accurate);      // `fast` (retired) reads as accurate
  EXPECT_EQ(m.joints[1].sweep, SweepMode::Accurate);      // the default
  EXPECT_TRUE((m.joints[0].origin.linear() * Vec3::UnitX()).isApprox(Vec3::UnitY(), 1e-12));  // yaw 90 deg
  EXPECT_EQ(m.joints[3].state_offset, 5);
  // Pairs: all pairs in different frames, minus the ignored one.
  ASSERT_EQ(m.pairs.size(), 5u);
  for (const BodyPair& p : m.pairs) {
    EXPECT_FALSE(m.bodies[p.a].name == "arm" && m.bodies[p.b].name == "tool");
    if (m.bodies[p.a].name == "arm" && m.bodies[p.b].name == "box") {
      EXPECT_EQ(p.lca, kWorld);
    }
  }
  EXPECT_EQ(m.commonAncestor(m.jointIndex("slide"), m.jointIndex("base")), m.jointIndex("base"));
}

struct BadCase {
  const char* what;
  std::string text;
  std::vector<std::string> expected;  // substrings of the message
};

TEST(Model, EveryMistakeGetsOneClearMessage) {
  const std::vector<BadCase> cases = {
      {"unknown joint type",
       edit("type: prismatic", "type: prismatik"),
       {"cell.yaml:14:", "joint 'slide'.type", "unknown joint type 'prismatik'"}},
      {"parent not yet defined",
       edit("parent: base", "parent: later"),
       {"cell.yaml:13:", "joint 'slide'.parent", "'later' is not a joint defined earlier"}},
      {"duplicate joint", edit("name: slide", "name: base"), {"cell.yaml:12:", "duplicate joint name 'base'"}},
      {"duplicate body", edit("name: tool", "name: arm"), {"cell.yaml:", "duplicate body name 'arm'"}},
      {"wrong vector length",
       edit("axis: [1, 0, 0]", "axis: [1, 0]"),
       {"cell.yaml:15:", "joint 'slide'.axis", "expected 3 numbers, got 2"}},
      {"zero axis", edit("axis: [1, 0, 0]", "axis: [0, 0, 0]"), {"cell.yaml:15:", "zero axis"}},
      {"negative radius",
       edit("radius: 0.05", "radius: -0.05"),
       {"cell.yaml:32:", "body 'arm'.radius", "negative radius"}},
      {"empty point list",
       edit("points: [[0, 0, 0], [1, 0, 0]]", "points: []"),
       {"cell.yaml:31:", "body 'arm'.points", "empty point list"}},
      {"unknown body in pairs",
       edit("ignore: [[arm, tool]]", "ignore: [[arm, tol]]"),
       {"cell.yaml:42:", "pairs.ignore[0]", "unknown body 'tol'"}},
      {"unknown frame", edit("frame: slide", "frame: slider"), {"body 'tool'.frame", "unknown joint 'slider'"}},
      {"not a number", edit("radius: 0.1", "radius: big"), {"cell.yaml:28:", "expected a number, got 'big'"}},
      {"NaN", edit("radius: 0.1", "radius: .nan"), {"cell.yaml:28:", "must be finite"}},
      {"missing field", edit("    type: revolute\n", ""), {"joint 'base'.type", "required field is missing"}},
      {"unknown field", edit("sweep: fast", "swep: fast"), {"cell.yaml:10:", "joints[0].swep", "unknown field"}},
      {"bad sweep mode", edit("sweep: fast", "sweep: quick"), {"unknown sweep mode 'quick'"}},
      {"limits reversed", edit("limits: [-1, 1]", "limits: [1, -1]"), {"lower limit is above the upper limit"}},
      {"version", edit("kccd: 1", "kccd: 2"), {"cell.yaml:1:", "unsupported format version '2'"}},
      {"no version", edit("kccd: 1\n", ""), {"model.kccd", "required field is missing"}},
      {"negative error", edit("error: 0.01", "error: -0.01"), {"joint 'pose'.error", "must be >= 0"}},
      {"axis on a 3-DOF joint", edit("    error: 0.02", "    axis: [0, 0, 1]"), {"rotation3d joint has no axis"}},
      {"YAML syntax", edit("name: t", "name: [t"), {"cell.yaml:", "YAML syntax error"}},
      {"world as joint name", edit("name: slide", "name: world"), {"'world' is reserved"}},
      {"pair with itself", edit("ignore: [[arm, tool]]", "ignore: [[arm, arm]]"), {"a body paired with itself"}},
      {"negative tolerance",
       edit("    radius: 0.05\n", "    radius: 0.05\n    tolerance: -0.001\n"),
       {"cell.yaml:33:", "body 'arm'.tolerance", "must be >= 0"}},
      {"pieces of a link in two frames",
       edit("    radius: 0.05\n  - name: tool\n", "    radius: 0.05\n    link: limb\n  - name: tool\n    link: limb\n"),
       {"body 'tool'.link", "piece of link 'limb' in frame 'slide'", "body 'arm' of that link is in frame 'base'"}},
      {"a link named like a whole body",
       edit("    radius: 0.05\n", "    radius: 0.05\n    link: floor\n"),
       {"cell.yaml:33:", "body 'arm'.link", "link 'floor' is also a whole body's name"}},
      {"empty link name",
       edit("    radius: 0.05\n", "    radius: 0.05\n    link: \"\"\n"),
       {"cell.yaml:33:", "body 'arm'.link", "must not be empty"}},
      {"same-frame include", edit("ignore: [[arm, tool]]", "include: [[floor, floor]]"), {"a body paired with itself"}},
      {"bad check", edit("ignore: [[arm, tool]]", "check: some"), {"pairs.check", "expected 'all' or 'none'"}},
      // The model used must be the model written: YAML's rules, not the first value that fits.
      {"duplicate key",
       edit("    radius: 0.1\n", "    radius: 0.1\n    radius: 0.9\n"),
       {"cell.yaml:29:", "bodies[0].radius", "duplicate key 'radius'"}},
      {"duplicate key, flow style",
       edit("{xyz: [0, 0, 0.5],", "{xyz: [0, 0, 0.5], xyz: [1, 1, 1],"),
       {"cell.yaml:8:32", "joints[0].origin.xyz", "duplicate key 'xyz'"}},
      {"duplicate version", edit("kccd: 1\n", "kccd: 1\nkccd: 2\n"), {"cell.yaml:2:1", "duplicate key 'kccd'"}},
      {"second bodies block", kGood + "bodies: []\n", {"cell.yaml:", "duplicate key 'bodies'"}},
      {"second document", kGood + "---\nkccd: 1\n", {"cell.yaml:", "a second YAML document"}},
      {"text after the end marker", kGood + "...\nradius: 3\n", {"cell.yaml:", "a second YAML document"}},
      {"deep nesting",
       edit("points: [[0, 0, 0]]", "points: " + std::string(100, '[') + std::string(100, ']')),
       {"cell.yaml:", "nested deeper than 64 levels"}},
      {"a list as a key",
       edit("name: t\n", "? [a, b]\n: t\n"),
       {"cell.yaml:2:", "a mapping key must be a plain value"}},
      {"length beyond the bound", edit("radius: 0.1", "radius: 2e6"), {"body 'floor'.radius", "largest length"}},
      {"coordinate beyond the bound",
       edit("points: [[0, 0, 0], [1, 0, 0]]", "points: [[0, 0, 0], [1e7, 0, 0]]"),
       {"body 'arm'.points[1][0]", "largest length"}},
      {"control byte in a name", edit("name: tool", "name: \"to\\x1bol\""), {"control character", "to\\x1bol"}},
      // A name must print as JSON (kccd info --json): bytes that are not UTF-8 are refused here.
      {"not UTF-8 in a name", edit("name: tool", "name: to\xffol"), {"cell.yaml:", "is not UTF-8 text", "to\\xffol"}},
      {"a surrogate in a name", edit("name: tool", "name: to\xed\xa0\x80l"), {"is not UTF-8 text"}},
      {"an overlong form in a name", edit("name: tool", "name: to\xc0\xafl"), {"is not UTF-8 text"}},
  };
  for (const BadCase& c : cases) {
    const std::string msg = loadError(c.text);
    for (const std::string& part : c.expected)
      EXPECT_NE(msg.find(part), std::string::npos) << c.what << ": '" << part << "' not in: " << msg;
    EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 0) << c.what << ": one line only";
  }
}

std::string edit_text(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

// visuals: appearance only, in a frame, one shape each; mesh paths relative to the model file.
// Pieces of a concave link: one `link:` name over bodies in one frame; the tolerance each body
// meets is kept; bodies in one frame are never paired, so pieces are never checked against
// each other.
TEST(Model, PiecesOfALinkAndTheirTolerances) {
  std::string text = edit("  - name: tool\n    frame: slide\n    points: [[0, 0, 0]]\n    radius: 0.02\n",
                          "  - name: tool/1\n    link: tool\n    frame: slide\n    points: [[0, 0, 0]]\n"
                          "    radius: 0.02\n    tolerance: 0.002\n  - name: tool/2\n    link: tool\n"
                          "    frame: slide\n    points: [[0.1, 0, 0]]\n    radius: 0.02\n");
  text.replace(text.find("ignore: [[arm, tool]]"), 21, "ignore: [[arm, tool/1]]");
  const Model m = parseModel(text, "pieces.yaml");
  const Body& a = m.bodies[m.bodyIndex("tool/1")];
  const Body& b = m.bodies[m.bodyIndex("tool/2")];
  EXPECT_EQ(a.linkName(), "tool");
  EXPECT_EQ(b.linkName(), "tool");
  EXPECT_EQ(m.bodies[m.bodyIndex("arm")].linkName(), "arm");
  EXPECT_DOUBLE_EQ(a.tolerance, 0.002);
  EXPECT_LT(b.tolerance, 0.0);  // not recorded
  const int ia = m.bodyIndex("tool/1"), ib = m.bodyIndex("tool/2");
  for (const BodyPair& p : m.pairs) EXPECT_FALSE((p.a == ia && p.b == ib) || (p.a == ib && p.b == ia));
  // A piece may not take a whole body's name as its link, nor a whole body a link's name.
  EXPECT_NE(loadError(edit("  - name: box\n    frame: turn", "  - name: box\n    link: arm\n    frame: base"))
                .find("body 'box'.link: link 'arm' is also a whole body's name"),
            std::string::npos);
  std::string later = text;
  later.replace(later.find("  - name: box\n"), 14, "  - name: tool\n");
  EXPECT_NE(loadError(later).find("'tool' is already the link of body 'tool/1'"), std::string::npos)
      << loadError(later);
}

TEST(Model, VisualsLoadAndTheirMistakesPointAtTheLine) {
  const std::string visuals = kGood + R"(visuals:
  - frame: base
    mesh: meshes/arm.dae
    scale: [0.001, 0.001, 0.001]
    origin: {xyz: [0, 0, 0.1], rpy: [0, 0, 0]}
    colour: [1, 0.5, 0]
  - frame: world
    box: [1, 2, 0.1]
  - frame: turn
    cylinder: {radius: 0.05, length: 0.2}
    colour: [0.2, 0.2, 0.2, 0.5]
  - frame: world
    sphere: 0.3
  - frame: slide
    mesh: /abs/tool.stl
)";
  const Model m = parseModel(visuals, "/models/cell/cell.yaml");
  ASSERT_EQ(m.visuals.size(), 5u);
  EXPECT_EQ(m.visuals[0].shape, Visual::Shape::Mesh);
  EXPECT_EQ(m.visuals[0].frame, m.jointIndex("base"));
  EXPECT_EQ(m.visuals[0].mesh, "/models/cell/meshes/arm.dae");
  EXPECT_DOUBLE_EQ(m.visuals[0].scale.x(), 0.001);
  EXPECT_DOUBLE_EQ(m.visuals[0].origin.translation().z(), 0.1);
  EXPECT_EQ(m.visuals[0].colour, (std::array<double, 4>{1, 0.5, 0, 1}));
  EXPECT_EQ(m.visuals[1].shape, Visual::Shape::Box);
  EXPECT_EQ(m.visuals[1].frame, kWorld);
  EXPECT_EQ(m.visuals[1].size, Vec3(1, 2, 0.1));
  EXPECT_EQ(m.visuals[2].shape, Visual::Shape::Cylinder);
  EXPECT_EQ(m.visuals[2].size, Vec3(0.05, 0.05, 0.2));
  EXPECT_DOUBLE_EQ(m.visuals[2].colour[3], 0.5);
  EXPECT_EQ(m.visuals[3].size, Vec3(0.3, 0.3, 0.3));
  EXPECT_EQ(m.visuals[4].mesh, "/abs/tool.stl");
  // Visuals change nothing that is checked.
  EXPECT_EQ(m.pairs.size(), parseModel(kGood, "cell.yaml").pairs.size());
  const int line = 44;  // the first visual's frame
  auto error = [&](const std::string& from, const std::string& to) {
    std::string text = visuals;
    text.replace(text.find(from), from.size(), to);
    return loadError(text);
  };
  auto expectIn = [](const std::string& message, const std::string& part) {
    EXPECT_NE(message.find(part), std::string::npos) << message << " (expected '" << part << "')";
  };
  expectIn(error("frame: base\n    mesh", "frame: bse\n    mesh"), "cell.yaml:" + std::to_string(line) + ":");
  expectIn(error("frame: base\n    mesh", "frame: bse\n    mesh"), "visuals[0].frame: unknown joint 'bse'");
  expectIn(error("    box: [1, 2, 0.1]\n", "    box: [1, 2, 0.1]\n    sphere: 1\n"),
           "exactly one of mesh, box, cylinder, sphere");
  expectIn(error("colour: [1, 0.5, 0]", "colour: [1, 1.5, 0]"), "visuals[0].colour[1]: must be in 0..1");
  expectIn(error("box: [1, 2, 0.1]", "box: [1, 0, 0.1]"), "visuals[1].box[1]: must be > 0");
  expectIn(error("    box: [1, 2, 0.1]\n", "    box: [1, 2, 0.1]\n    scale: [1, 1, 1]\n"),
           "a scale applies to meshes only");
  expectIn(error("scale: [0.001, 0.001, 0.001]", "scale: [0.001, 0, 0.001]"), "factors must be non-zero");
  expectIn(error("cylinder: {radius: 0.05, length: 0.2}", "cylinder: {radius: 0.05}"), "cylinder.length");
  expectIn(error("sphere: 0.3", "sphere: 1e7"), "beyond the largest length");
  expectIn(error("mesh: meshes/arm.dae", "mesh: package://robot/arm.dae"),
           "package:// paths are resolved by kccd import");
  EXPECT_EQ(
      parseModel(edit_text(visuals, "mesh: /abs/tool.stl", "mesh: file:///abs/tool.stl"), "c.yaml").visuals[4].mesh,
      "/abs/tool.stl");
  expectIn(error("    sphere: 0.3\n", "    sphere: 0.3\n    texture: wood\n"), "unknown field");
}

TEST(Model, AxesOfAnyScaleNormalise) {
  for (const char* axis : {"[0, 0, 1e-150]", "[0, 0, 1e200]", "[1e-300, 0, 3e-300]", "[1.5e308, 0, 1.5e308]"}) {
    const Model m = parseModel(edit("axis: [0, 0, 2]", std::string("axis: ") + axis), "cell.yaml");
    EXPECT_NEAR(m.joints[0].axis.norm(), 1.0, 1e-15) << axis;
  }
  EXPECT_NEAR(parseModel(edit("axis: [0, 0, 2]", "axis: [1e200, 1e200, 0]"), "c").joints[0].axis.x(), std::sqrt(0.5),
              1e-15);
  // Angles of any finite size are angles: limits as exporters write "unlimited".
  EXPECT_NO_THROW(parseModel(edit("limits: [-1, 1]", "limits: [-3.4e38, 3.4e38]"), "cell.yaml"));
}

TEST(Model, NotARegularFileIsRefused) {
  try {
    loadModel("/dev/zero");  // would never end
    FAIL() << "loaded /dev/zero";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/zero: not a regular file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadModel(::testing::TempDir()), ModelError);
}

TEST(Model, MissingFileNamesThePath) {
  try {
    loadModel("/nonexistent/robot.yaml");
    FAIL() << "loaded a missing file";
  } catch (const ModelError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.yaml: cannot open"), std::string::npos);
  }
}

TEST(Model, SampleScenesHaveTheirDocumentedSize) {
  struct Expect {
    const char* file;
    std::size_t bodies;
    int dof;
    int points;
  };
  for (const Expect& e : {Expect{"humanoid.yaml", 26, 20, 80}, Expect{"industrial_cell.yaml", 13, 12, 50},
                          Expect{"demo_arm.yaml", 7, 3, 18}}) {
    const Model m = loadModel(std::string(KCCD_DATA_DIR) + "/" + e.file);
    int points = 0;
    for (const Body& b : m.bodies) points += static_cast<int>(b.points.size());
    EXPECT_EQ(m.bodies.size(), e.bodies) << e.file;
    EXPECT_EQ(m.stateSize(), e.dof) << e.file;
    EXPECT_EQ(points, e.points) << e.file;
    EXPECT_FALSE(m.pairs.empty()) << e.file;
  }
}

}  // namespace
}  // namespace kccd
