// Meshes in the formats robot descriptions use (OBJ, COLLADA, PLY, glTF binary, STL), read
// through Assimp: each file written here holds a known solid (a box, placed by the file's own
// node transforms and units); the points read are exactly its corners, the fitted SSCH contains
// every one of them (an independent point-to-hull distance), and a URDF mixing all formats
// imports with every link containing its mesh.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kccd/input_error.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/part.hpp"
#include "kccd/modelling/urdf_import.hpp"
#include "support/files.hpp"
#include "support/reference_distance.hpp"

namespace km = kccd::modelling;
using kccd::Vec3;

namespace {

std::filesystem::path scratch() { return kccd::testing::scratchFolder("kccd_meshes"); }

std::string write(const std::string& name, const std::string& text) {
  return kccd::testing::writeScratch("kccd_meshes", name, text);
}

// The box [0, size.x] x [0, size.y] x [0, size.z]: corner i has bit k of i set for the far side on axis k.
std::vector<Vec3> corners(const Vec3& size) {
  std::vector<Vec3> c;
  for (int i = 0; i < 8; ++i) c.emplace_back(i & 1 ? size.x() : 0, i & 2 ? size.y() : 0, i & 4 ? size.z() : 0);
  return c;
}
// Its 12 triangles (corner indices), outward-wound.
const int kTriangles[12][3] = {{0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}, {0, 4, 5}, {0, 5, 1},
                               {2, 3, 7}, {2, 7, 6}, {0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}};

std::string objBox(const Vec3& size, const std::string& object = "") {
  std::ostringstream s;
  s.precision(17);
  if (!object.empty()) s << "o " << object << "\n";
  for (const Vec3& v : corners(size)) s << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
  return s.str();
}
std::string objFaces(int first = 1) {
  std::ostringstream s;
  for (const auto& t : kTriangles) s << "f " << t[0] + first << " " << t[1] + first << " " << t[2] + first << "\n";
  return s.str();
}

// COLLADA with a unit and an up axis, the box placed by a node translation (in the file's units).
std::string daeBox(const Vec3& size, double meter, const std::string& up, const Vec3& translate) {
  std::ostringstream s;
  s.precision(17);
  s << R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="unit" meter=")"
    << meter << R"("/><up_axis>)" << up << R"(</up_axis></asset>
  <library_geometries>
    <geometry id="box-mesh" name="box">
      <mesh>
        <source id="box-pos">
          <float_array id="box-pos-array" count="24">)";
  for (const Vec3& v : corners(size)) s << v.x() << " " << v.y() << " " << v.z() << " ";
  s << R"(</float_array>
          <technique_common><accessor source="#box-pos-array" count="8" stride="3">
            <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
          </accessor></technique_common>
        </source>
        <vertices id="box-vtx"><input semantic="POSITION" source="#box-pos"/></vertices>
        <triangles count="12"><input semantic="VERTEX" source="#box-vtx" offset="0"/><p>)";
  for (const auto& t : kTriangles) s << t[0] << " " << t[1] << " " << t[2] << " ";
  s << R"(</p></triangles>
      </mesh>
    </geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="Scene" name="Scene">
      <node id="box" name="box"><translate>)"
    << translate.x() << " " << translate.y() << " " << translate.z()
    << R"(</translate><instance_geometry url="#box-mesh"/></node>
    </visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#Scene"/></scene>
</COLLADA>
)";
  return s.str();
}

std::string plyBox(const Vec3& size) {
  std::ostringstream s;
  s.precision(17);
  s << "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& v : corners(size)) s << v.x() << " " << v.y() << " " << v.z() << "\n";
  for (const auto& t : kTriangles) s << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return s.str();
}

// Binary glTF: one node with a translation holding the box mesh (float positions, uint32 indices).
std::string glbBox(const Vec3& size, const Vec3& translation) {
  std::string bin;
  auto put = [&bin](const void* p, std::size_t n) { bin.append(static_cast<const char*>(p), n); };
  for (const Vec3& v : corners(size)) {
    const float f[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
    put(f, sizeof f);
  }
  for (const auto& t : kTriangles)
    for (const int k : t) {
      const std::uint32_t i = static_cast<std::uint32_t>(k);
      put(&i, 4);
    }
  std::ostringstream j;
  j.precision(17);
  j << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"translation":[)"
    << translation.x() << "," << translation.y() << "," << translation.z()
    << R"(]}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"buffers":[{"byteLength":)"
    << bin.size()
    << R"(}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96},{"buffer":0,"byteOffset":96,"byteLength":144}],)"
    << R"("accessors":[{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[0,0,0],"max":[)" << size.x()
    << "," << size.y() << "," << size.z() << R"(]},{"bufferView":1,"componentType":5125,"count":36,"type":"SCALAR"}]})";
  std::string json = j.str();
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin += '\0';
  std::string out;
  auto u32 = [&out](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  u32(0x46546C67u);  // "glTF"
  u32(2);
  u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  u32(static_cast<std::uint32_t>(json.size()));
  u32(0x4E4F534Au);  // "JSON"
  out += json;
  u32(static_cast<std::uint32_t>(bin.size()));
  u32(0x004E4942u);  // "BIN"
  out += bin;
  return out;
}

std::string binaryStlBox(const Vec3& size) {
  std::string out(80, ' ');
  const std::uint32_t n = 12;
  out.append(reinterpret_cast<const char*>(&n), 4);
  const std::vector<Vec3> c = corners(size);
  for (const auto& t : kTriangles) {
    const float normal[3] = {0, 0, 0};
    out.append(reinterpret_cast<const char*>(normal), 12);
    for (const int k : t) {
      const float f[3] = {static_cast<float>(c[k].x()), static_cast<float>(c[k].y()), static_cast<float>(c[k].z())};
      out.append(reinterpret_cast<const char*>(f), 12);
    }
    out.append(2, '\0');
  }
  return out;
}

// Every point read is one of `expected` (to single precision) and every one of them is read.
void expectExactly(const km::Part& part, const std::vector<Vec3>& expected) {
  ASSERT_FALSE(part.points.empty());
  std::vector<bool> seen(expected.size(), false);
  for (const Vec3& p : part.points) {
    double best = 1e300;
    std::size_t at = 0;
    for (std::size_t k = 0; k < expected.size(); ++k)
      if ((p - expected[k]).norm() < best) best = (p - expected[k]).norm(), at = k;
    EXPECT_LT(best, 1e-6 * (1.0 + expected[at].norm())) << p.transpose();
    seen[at] = true;
  }
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_TRUE(seen[k]) << "corner " << expected[k].transpose() << " not read";
}

// The fitted SSCH contains every expected point (independent point-to-hull distance).
void expectFitContains(const km::Part& part, const std::vector<Vec3>& expected) {
  km::FitOptions o;
  o.points = 4;
  const km::FitResult fit = km::fit(part, o);
  for (const Vec3& p : expected)
    EXPECT_LE(static_cast<double>(kccd::testing::referencePointHullDistance(p, fit.points)), fit.radius + 1e-12)
        << p.transpose();
}

std::vector<Vec3> moved(std::vector<Vec3> pts, const Vec3& by, double scale = 1.0) {
  for (Vec3& p : pts) p = scale * (p + by);
  return pts;
}

std::string errorOf(const std::string& path, const km::ReadOptions& options = {}) {
  try {
    (void)km::readPart(path, options);
  } catch (const kccd::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(MeshFormats, EachFormatReadsTheBoxItHolds) {
  const Vec3 size(0.3, 0.2, 0.1);
  struct Case {
    std::string file, bytes;
    std::vector<Vec3> expected;
  };
  const std::vector<Case> cases = {
      {"box.obj", objBox(size) + objFaces(), corners(size)},
      {"box.ply", plyBox(size), corners(size)},
      {"box.stl", binaryStlBox(size), corners(size)},
      {"box.glb", glbBox(size, Vec3(1, -2, 0.5)), moved(corners(size), Vec3(1, -2, 0.5))},
      // Millimetres, the node moved by 100 mm: the unit applies to the translation too.
      {"box_mm.dae", daeBox(size * 1000, 0.001, "Z_UP", Vec3(100, 0, 0)), moved(corners(size), Vec3(0.1, 0, 0))},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const km::Part part = km::readPart(write(c.file, c.bytes));
    EXPECT_EQ(part.triangles, 12);
    expectExactly(part, c.expected);
    expectFitContains(part, c.expected);
  }
}

TEST(MeshFormats, ColladaUpAxisIsNotRotatedAndItsUnitIsApplied) {
  // The same coordinates with each up axis read the same (the link frame is the file's frame,
  // as ROS tools place COLLADA meshes); the unit scales them.
  const Vec3 size(0.4, 0.2, 0.1);
  for (const std::string up : {"Z_UP", "Y_UP", "X_UP"}) {
    SCOPED_TRACE(up);
    const km::Part metres = km::readPart(write("up_" + up + ".dae", daeBox(size, 1.0, up, Vec3::Zero())));
    expectExactly(metres, corners(size));
    const km::Part inches = km::readPart(write("in_" + up + ".dae", daeBox(size, 0.0254, up, Vec3::Zero())));
    expectExactly(inches, corners(size * 0.0254));
  }
}

TEST(MeshFormats, UrdfScaleAppliesAfterTheFileTransforms) {
  const Vec3 size(0.3, 0.2, 0.1);
  const km::Part part = km::readPart(write("scaled.glb", glbBox(size, Vec3(1, 0, 0))), {.scale = Vec3(2, 1, -1)});
  std::vector<Vec3> expected = moved(corners(size), Vec3(1, 0, 0));
  for (Vec3& p : expected) p = p.cwiseProduct(Vec3(2, 1, -1));
  expectExactly(part, expected);
}

TEST(MeshFormats, SeveralObjectsArePartsToPickOrMerge) {
  const std::string two = write(
      "two.obj", objBox(Vec3(1, 1, 1), "left") + objFaces(1) + objBox(Vec3(0.5, 0.5, 0.5), "right") + objFaces(9));
  const std::string e = errorOf(two);
  EXPECT_EQ(e.rfind(two + ": holds 2 top-level parts", 0), 0u) << e;
  EXPECT_NE(e.find("'left'"), std::string::npos) << e;
  EXPECT_NE(e.find("--merge"), std::string::npos) << e;
  EXPECT_EQ(km::readPart(two, {.merge = true}).triangles, 24);
  const km::Part right = km::readPart(two, {.part = "right"});
  EXPECT_EQ(right.triangles, 12);
  expectExactly(right, corners(Vec3(0.5, 0.5, 0.5)));
  const std::string missing = errorOf(two, {.part = "middle"});
  EXPECT_EQ(missing, two + ": no node named 'middle'");
}

TEST(MeshFormats, BadMeshesAreOneLineErrorsNamingTheFile) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"empty.obj", "# nothing here\n"},
      {"points.obj", "v 0 0 0\nv 1 0 0\np 1 2\n"},
      {"garbage.dae", "<COLLADA><library_geometries><geometry></COLLADA"},
      {"garbage.glb", std::string("glTF\x02\0\0\0\xff\xff\xff\x7f", 12)},
      {"garbage.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n"},
      {"nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"inf.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 1\nproperty list uchar int vertex_indices\nend_header\n1e39 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
      // Assimp's PLY reader never returns on this header (found by fuzz_part): refused before it.
      {"element_without_count.ply", "ply\nformat ascii 1.0\nelement 0\n0.3 0.2 0\n3 0 2 6\n"},
      {"property_first.ply", "ply\nformat ascii 1.0\nproperty float x\nelement vertex 1\nend_header\n1\n"},
      {"no_end.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"},
      {"empty.stl", ""},
  };
  for (const auto& [file, bytes] : cases) {
    const std::string path = write(file, bytes);
    const std::string e = errorOf(path);
    SCOPED_TRACE(file + ": " + e);
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u);
    EXPECT_EQ(e.find('\n'), std::string::npos);
  }
}

// Assimp reads in a child process: a read that takes longer than its limit is killed and is a
// one-line error (here a limit of 0 s); the same file within the limit reads as usual.
TEST(MeshFormats, ReadsBeyondTheTimeLimitAreStopped) {
  const std::string box = write("limited.obj", objBox(Vec3(0.3, 0.2, 0.1)) + objFaces());
  km::ReadOptions options;
  options.mesh_time_limit_s = 0.0;
  const std::string e = errorOf(box, options);
  EXPECT_EQ(e, box + ": reading the mesh took longer than 0 s (a malformed file?)");
  options.mesh_time_limit_s = 60.0;
  EXPECT_EQ(km::readPart(box, options).triangles, 12);
}

TEST(MeshFormats, UrdfMixingEveryFormatImports) {
  const Vec3 size(0.2, 0.1, 0.05);
  write("mix_box.obj", objBox(size) + objFaces());
  write("mix_box.ply", plyBox(size));
  write("mix_box.stl", binaryStlBox(size));
  write("mix_box.glb", glbBox(size, Vec3(0.1, 0, 0)));
  write("mix_box.dae", daeBox(size * 1000, 0.001, "Y_UP", Vec3(0, 0, 0)));
  std::ostringstream urdf;
  urdf << "<robot name=\"mix\">\n  <material name=\"orange\"><color rgba=\"1 0.5 0 1\"/></material>\n"
       << "  <link name=\"base\"><collision><geometry><mesh filename=\"mix_box.obj\"/></geometry></collision>"
       << "<visual><origin xyz=\"0 0 0.01\"/><geometry><mesh filename=\"mix_box.dae\" scale=\"2 2 2\"/></geometry>"
       << "<material name=\"orange\"/></visual><visual><geometry><cylinder radius=\"0.1\" "
          "length=\"0.3\"/></geometry></visual>"
       << "</link>\n";
  const char* files[] = {"mix_box.ply", "mix_box.stl", "mix_box.glb", "mix_box.dae"};
  std::string parent = "base";
  for (int i = 0; i < 4; ++i) {
    const std::string link = "l" + std::to_string(i);
    urdf << "  <link name=\"" << link << "\"><collision><geometry><mesh filename=\"" << files[i]
         << "\" scale=\"2 2 2\"/></geometry></collision></link>\n"
         << "  <joint name=\"j" << i << "\" type=\"revolute\"><parent link=\"" << parent << "\"/><child link=\"" << link
         << "\"/><origin xyz=\"0 0 0.3\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" "
            "velocity=\"1\"/></joint>\n";
    parent = link;
  }
  urdf << "</robot>\n";
  km::ImportOptions options;
  options.fit.points = 4;
  const kccd::Model m = kccd::parseModel(km::importUrdf(write("mix.urdf", urdf.str()), options), "imported");
  ASSERT_EQ(m.bodies.size(), 5u);
  // The base link's two <visual>s: the DAE with its scale, origin and material colour, a cylinder.
  ASSERT_EQ(m.visuals.size(), 2u);
  EXPECT_EQ(m.visuals[0].shape, kccd::Visual::Shape::Mesh);
  EXPECT_EQ(m.visuals[0].frame, kccd::kWorld);
  EXPECT_TRUE(std::filesystem::path(m.visuals[0].mesh).is_absolute());
  EXPECT_TRUE(std::filesystem::equivalent(m.visuals[0].mesh, scratch() / "mix_box.dae"));
  EXPECT_EQ(m.visuals[0].scale, Vec3(2, 2, 2));
  EXPECT_NEAR(m.visuals[0].origin.translation().z(), 0.01, 1e-12);
  EXPECT_EQ(m.visuals[0].colour, (std::array<double, 4>{1, 0.5, 0, 1}));
  EXPECT_EQ(m.visuals[1].shape, kccd::Visual::Shape::Cylinder);
  EXPECT_EQ(m.visuals[1].size, Vec3(0.1, 0.1, 0.3));
  options.visuals = false;
  EXPECT_TRUE(kccd::parseModel(km::importUrdf((scratch() / "mix.urdf").string(), options), "imported").visuals.empty());
  auto contains = [&](const std::string& body, const std::vector<Vec3>& pts) {
    const kccd::Body& b = m.bodies[m.bodyIndex(body)];
    for (const Vec3& p : pts)
      EXPECT_LE(static_cast<double>(kccd::testing::referencePointHullDistance(p, b.points)), b.radius + 1e-12)
          << body << " misses " << p.transpose();
  };
  contains("base", corners(size));
  contains("l0", moved(corners(size), Vec3::Zero(), 2.0));
  contains("l1", moved(corners(size), Vec3::Zero(), 2.0));
  contains("l2", moved(corners(size), Vec3(0.1, 0, 0), 2.0));
  contains("l3", moved(corners(size), Vec3::Zero(), 2.0));
}

}  // namespace
