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
