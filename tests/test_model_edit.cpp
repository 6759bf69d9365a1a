// In-place model edits (kccd fit --model, kccd pairs --write) in block and flow style.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "kccd/model.hpp"
#include "kccd/modelling/yaml_edit.hpp"
#include "support/files.hpp"

namespace km = kccd::modelling;
using kccd::Model;
using kccd::Vec3;

TEST(YamlEdit, BodyGeometryKeepsEverythingElse) {
  const std::string text = kccd::testing::readText(std::string(KCCD_DATA_DIR) + "/demo_arm.yaml");
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
  EXPECT_THROW(km::withBodyGeometry(text, "demo_arm.yaml", "nobody", "[[0, 0, 0]]", "0.1"), km::EditError);
  EXPECT_THROW(km::withBodyGeometry(text, "demo_arm.yaml", "forearm", "[]", "0.1"), km::EditError);
}

// A body's tolerance is the bound its old geometry met: the new geometry's replaces it, or it goes
// when none is given; a body without one gains it. Block and flow style, comments kept.
TEST(YamlEdit, NewGeometryNeverKeepsTheOldTolerance) {
  const std::string text =
      "kccd: 1\nname: t\njoints:\n  - {name: j, parent: world, type: revolute, axis: [0, 0, 1]}\nbodies:\n"
      "  - name: a   # the base\n    frame: world\n    points: [[0, 0, 0], [1, 0, 0]]\n    radius: 0.1  # metres\n"
      "    tolerance: 0.004   # as fitted\n"
      "  - {name: b, frame: j, points: [[0, 0, 2]], radius: 0.2, tolerance: 0.003}\n"
      "  - name: c\n    frame: j\n    points: [[0, 0, 4]]\n    radius: 0.3\n"
      "  - {name: d, frame: j, points: [[0, 0, 6]], radius: 0.3}\n";
  const auto tolerance = [](const std::string& t, const char* body) {
    const Model m = kccd::parseModel(t, "edited");
    return m.bodies[static_cast<std::size_t>(m.bodyIndex(body))].tolerance;
  };
  for (const char* body : {"a", "b"}) {
    const std::string replaced = km::withBodyGeometry(text, "t", body, "[[5, 5, 5]]", "0.5", "0.002");
    EXPECT_EQ(tolerance(replaced, body), 0.002) << body << "\n" << replaced;
    const std::string dropped = km::withBodyGeometry(text, "t", body, "[[5, 5, 5]]", "0.5");
    EXPECT_LT(tolerance(dropped, body), 0.0) << body << "\n" << dropped;  // not said
    EXPECT_EQ(tolerance(dropped, body == std::string("a") ? "b" : "a"), body == std::string("a") ? 0.003 : 0.004);
    EXPECT_NE(dropped.find("# metres"), std::string::npos);
  }
  EXPECT_EQ(km::withBodyGeometry(text, "t", "a", "[[5, 5, 5]]", "0.5").find("as fitted"), std::string::npos);
  for (const char* body : {"c", "d"}) {
    const std::string added = km::withBodyGeometry(text, "t", body, "[[5, 5, 5]]", "0.5", "0.001");
    EXPECT_EQ(tolerance(added, body), 0.001) << body << "\n" << added;
    EXPECT_LT(tolerance(km::withBodyGeometry(text, "t", body, "[[5, 5, 5]]", "0.5"), body), 0.0);
  }
}

// Names that need quoting are quoted with '"' and '\\' escaped (a pair list that loads back).
TEST(YamlEdit, QuotedNamesEscapeQuotesAndBackslashes) {
  const std::string text =
      "kccd: 1\nname: t\njoints:\n  - {name: j, parent: world, type: revolute, axis: [0, 0, 1]}\nbodies:\n"
      "  - {name: 'say \"hi\"', frame: world, points: [[0, 0, 0]], radius: 0.1}\n"
      "  - {name: 'back\\slash', frame: j, points: [[0, 0, 2]], radius: 0.2}\n";
  const std::string edited = km::withIgnoreList(text, "t", {{"say \"hi\"", "back\\slash"}});
  EXPECT_TRUE(kccd::parseModel(edited, "edited").pairs.empty()) << edited;
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
  edited = km::withIgnoreList(edited, "block", {{"a", "b"}});
  m = kccd::parseModel(edited, "edited");
  EXPECT_TRUE(m.pairs.empty());
  edited = km::withIgnoreList(edited, "block", {});
  EXPECT_EQ(kccd::parseModel(edited, "edited").pairs.size(), 1u);
  const std::string flow = block + "pairs: {check: all}\n";
  EXPECT_TRUE(kccd::parseModel(km::withIgnoreList(flow, "flow", {{"b", "a"}}), "f").pairs.empty());
  const std::string nested = block + "pairs:\n  check: all   # every pair\n";
  const std::string with = km::withIgnoreList(nested, "nested", {{"a", "b"}});
  EXPECT_TRUE(kccd::parseModel(with, "n").pairs.empty());
  EXPECT_NE(with.find("# every pair"), std::string::npos);
  EXPECT_THROW(km::withIgnoreList(block, "block", {{"a", "nobody"}}), km::EditError);
}
