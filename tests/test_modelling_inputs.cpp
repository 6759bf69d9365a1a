// Bad modelling inputs: CAD parts and URDFs that must be refused with one line naming the file,
// never read as a different model, crash or hang.
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "support/files.hpp"

#include "kccd/modelling/part.hpp"
#include "kccd/modelling/urdf_import.hpp"

namespace km = kccd::modelling;

namespace {

std::filesystem::path scratch() { return kccd::testing::scratchFolder("kccd_inputs"); }

std::string write(const std::string& name, const std::string& text) {
  return kccd::testing::writeScratch("kccd_inputs", name, text);
}

template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

std::string partError(const std::string& name, const std::string& text, const km::ReadOptions& o = {}) {
  const std::string path = write(name, text);
  return errorOf([&] { km::readPart(path, o); });
}

std::string urdfError(const std::string& name, const std::string& text) {
  const std::string path = write(name, text);
  return errorOf(
      [&] { km::importUrdf(path, {.fit = {.method = km::FitMethod::Tolerance, .points = 2, .max_pieces = 8}}); });
}

const std::string kIv = "#Inventor V2.1 ascii\n";

// One line, naming the file.
void expectOneLine(const std::string& message, const std::string& file) {
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_NE(message.find(file), std::string::npos) << message;
}

}  // namespace

TEST(PartInputs, NegativeAndOverflowingSizesAreRefused) {
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {kIv + "Sphere { radius -1 }\n", "Sphere: radius: -1 is negative"},
      {kIv + "Sphere { radius 1e39 }\n", ":2: a number is out of single-precision range"},
      {kIv + "Cube { width -1 }\n", "Cube: width: -1 is negative"},
      {kIv + "Cylinder { height -2 }\n", "Cylinder: height: -2 is negative"},
      {kIv + "DEF tip Cone { bottomRadius -0.5 }\n", "Cone 'tip': bottomRadius: -0.5 is negative"},
      {kIv + "Scale { scaleFactor 1e39 1 1 }\nCube {}\n", "out of single-precision range"},
      {"#VRML V2.0 utf8\nShape { geometry Box { size 1 -1 1 } }\n", "VRMLBox: size y: -1 is negative"},
      {"#VRML V2.0 utf8\nShape { geometry Sphere { radius -3 } }\n", "VRMLSphere: radius: -3 is negative"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string name = "size" + std::to_string(i++) + (c.text[1] == 'V' ? ".wrl" : ".iv");
    const std::string message = partError(name, c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    expectOneLine(message, name);
  }
  EXPECT_NE(partError("scaled.iv", kIv + "Cube {}\n", {.scale = kccd::Vec3(1, 0, 1)}).find("non-zero"),
            std::string::npos);
  EXPECT_NE(partError("scaled.stl", "solid s\nendsolid\n", {.scale = kccd::Vec3(1, NAN, 1)}).find("finite"),
            std::string::npos);
  // A zero radius is a point: exact, and still read.
  EXPECT_EQ(km::readPart(write("point.iv", kIv + "Sphere { radius 0 }\n")).balls.size(), 1u);
}

TEST(PartInputs, IncludesAreRefused) {
  EXPECT_NE(
      partError("self.iv", kIv + "File { name \"self.iv\" }\n").find("self.iv:2: File: includes are not supported"),
      std::string::npos);
  EXPECT_NE(partError("zero.iv", kIv + "Separator {\n  File { name \"/dev/zero\" }\n}\n").find("zero.iv:3: File"),
            std::string::npos);
  EXPECT_NE(partError("missing.iv", kIv + "Separator { Cube {} File { name \"nowhere.iv\" } }\n").find("File"),
            std::string::npos);
  EXPECT_NE(partError("inline.wrl", "#VRML V2.0 utf8\nShape { geometry Box {} }\nInline { url \"missing.wrl\" }\n")
                .find("inline.wrl:3: Inline"),
            std::string::npos);
  EXPECT_NE(partError("extern.wrl", "#VRML V2.0 utf8\nEXTERNPROTO P [] \"p.wrl\"\n").find("EXTERNPROTO"),
            std::string::npos);
  EXPECT_NE(
      partError("www.wrl", "#VRML V1.0 ascii\nSeparator { Cube {} WWWInline { name \"x.wrl\" } }\n").find("WWWInline"),
      std::string::npos);
  // A binary Open Inventor File node: refused before Coin follows it.
  std::string binary = "#Inventor V2.1 binary  \n";
  binary += std::string("\0\0\0\4File", 8);
  EXPECT_NE(partError("binary.iv", binary).find("File node at byte 24"), std::string::npos);
  // A DEF name that reads like an include is not one.
  EXPECT_EQ(km::readPart(write("named.iv", kIv + "DEF File Cube {}\n")).triangles, 12);
}

TEST(PartInputs, NestingIsBoundedBeforeCoin) {
  std::string deep = kIv;
  for (int i = 0; i < 20000; ++i) deep += "Separator {\n";
  deep += "Cube {}\n";
  for (int i = 0; i < 20000; ++i) deep += "}\n";
  EXPECT_NE(partError("deep.iv", deep).find("deep.iv:258: nested deeper than 256 levels"), std::string::npos);
  std::string fine = kIv;
  for (int i = 0; i < 200; ++i) fine += "Separator { ";
  fine += "Cube {}";
  for (int i = 0; i < 200; ++i) fine += " }";
  EXPECT_EQ(km::readPart(write("fine.iv", fine)).triangles, 12);
  // Braces in strings and comments do not count; a stray closing brace is an error, not the end.
  EXPECT_EQ(km::readPart(write("strings.iv", kIv + "# {{{{\nInfo { string \"}}} {{\" }\nCube {}\n")).triangles, 12);
  EXPECT_NE(partError("stray.iv", kIv + "Separator { Cube {} } }\nSeparator { Sphere {} }\n")
                .find("stray.iv:2: '}' closes nothing"),
            std::string::npos);
}

TEST(PartInputs, CoordinateIndicesOutsideTheirCoordinatesAreRefused) {
  const std::string coords = "Coordinate3 { point [0 0 0, 1 0 0, 0 1 0, 0 0 1] }\n";
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {kIv + coords + "IndexedFaceSet { coordIndex [0, 1, 2, -1, 0, 1, 1000000, -1] }\n",
       "IndexedFaceSet: coordIndex[6]: 1000000 is not a coordinate index (4 coordinates)"},
      {kIv + coords + "IndexedFaceSet { coordIndex [0, 1, -7, -1] }\n", "coordIndex[2]: -7"},
      {kIv + coords + "IndexedTriangleStripSet { coordIndex [0, 1, 2, 4] }\n",
       "IndexedTriangleStripSet: coordIndex[3]"},
      {kIv + coords + "IndexedLineSet { coordIndex [0, 9] }\n", "IndexedLineSet: coordIndex[1]"},
      {kIv + "IndexedFaceSet { vertexProperty VertexProperty { vertex [0 0 0, 1 0 0, 0 1 0] } coordIndex [0, 1, 3] }\n",
       "coordIndex[2]: 3 is not a coordinate index (3 coordinates)"},
      {kIv + coords + "FaceSet { numVertices [3, 3] }\n", "FaceSet: numVertices: 6 vertices"},
      {kIv + coords + "TriangleStripSet { startIndex 2 numVertices [3] }\n", "TriangleStripSet: numVertices"},
      {kIv + coords + "QuadMesh { verticesPerRow 3 verticesPerColumn 3 }\n",
       "QuadMesh: verticesPerColumn x verticesPerRow"},
      // Faces and strips of fewer than 3 vertices: Coin reads past its arrays (SIGSEGV) or
      // allocates without end (found by fuzz_part).
      {kIv + coords + "FaceSet { numVertices [2] }\n", "FaceSet: numVertices[0]: 2 vertices, at least 3 needed"},
      {kIv + coords + "FaceSet { numVertices [3, 0] }\n", "FaceSet: numVertices[1]: 0 vertices"},
      {kIv + coords + "FaceSet { numVertices [3, -1] }\n", "numVertices[1]: -1 (the rest) leaves 1 vertices"},
      {kIv + coords + "TriangleStripSet { numVertices [2] }\n", "TriangleStripSet: numVertices[0]: 2 vertices"},
      {kIv + coords + "LineSet { numVertices [1] }\n", "LineSet: numVertices[0]: 1 vertices, at least 2"},
      {"#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coord Coordinate { point [0 0 0, 1 0 0, 0 1 0] }"
       " coordIndex [0 1 5 -1] } }\n",
       "VRMLIndexedFaceSet: coordIndex[2]: 5"},
      {"#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coordIndex [0 1 2 -1] } }\n",
       "coordIndex[0]: 0 is not a coordinate index (0 coordinates)"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string name = "index" + std::to_string(i++) + (c.text[1] == 'V' ? ".wrl" : ".iv");
    const std::string message = partError(name, c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    expectOneLine(message, name);
  }
  // Valid indices still read.
  EXPECT_EQ(km::readPart(write("ok.iv", kIv + coords + "IndexedFaceSet { coordIndex [0, 1, 2, -1, 0, 2, 3, -1] }\n"))
                .triangles,
            2);
}

TEST(PartInputs, OnlyRegularFilesOfBoundedSize) {
  EXPECT_NE(errorOf([] { km::readPart("/dev/zero"); }).find("/dev/zero: not a regular file"), std::string::npos);
  const std::string dir = (scratch() / "dir.iv").string();
  std::filesystem::create_directories(dir);
  EXPECT_NE(errorOf([&] { km::readPart(dir); }).find("a folder, not a file"), std::string::npos);
  const std::string fifo = (scratch() / "fifo.iv").string();
  ::unlink(fifo.c_str());
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(errorOf([&] { km::readPart(fifo); }).find("not a regular file"), std::string::npos);  // no hang
  EXPECT_NE(
      errorOf([&] { km::readInputFile(write("big.iv", std::string(2000, ' ')), 1000); }).find("larger than 1000 bytes"),
      std::string::npos);
}

TEST(PartInputs, NurbsSurfacesAreCoveredByTheirControlPoints) {
  // Coin tessellates NURBS with OpenGL (a crash without a display): the control net covers them.
  const std::string nurbs = kIv +
                            "Coordinate3 { point [0 0 0, 1 0 0, 0 1 0, 1 1 1] }\n"
                            "NurbsSurface { numUControlPoints 2 numVControlPoints 2 uKnotVector [0 0 1 1] "
                            "vKnotVector [0 0 1 1] }\n";
  const km::Part part = km::readPart(write("nurbs.iv", nurbs));
  EXPECT_EQ(part.primitives, 1);
  ASSERT_EQ(part.points.size(), 4u);
  EXPECT_NEAR((part.points[3] - kccd::Vec3(1, 1, 1)).norm(), 0, 1e-6);
  EXPECT_NE(partError("nurbs_bad.iv", kIv + "Coordinate3 { point [0 0 0] }\nNurbsSurface { numUControlPoints 2 "
                                            "numVControlPoints 2 }\n")
                .find("numUControlPoints x numVControlPoints"),
            std::string::npos);
}

TEST(PartInputs, MessagesEscapeControlBytes) {
  const std::string message = partError("ctl.iv", kIv + "DEF a\x1b[31m Cube { width -1 }\n");
  EXPECT_EQ(message.find('\x1b'), std::string::npos) << message;
  EXPECT_EQ(kccd::printable("a\x1b\n\x7f"), "a\\x1b\\x0a\\x7f");  // the one printable every message uses
}

namespace {

const std::string kLink = "<link name=\"a\">\n  <collision><geometry><box size=\"1 1 1\"/></geometry></collision>\n";

std::string robotWith(const std::string& geometry) {
  return "<robot name=\"r\">\n" + kLink + "  <collision>\n    <geometry>" + geometry +
         "</geometry>\n  </collision>\n</link>\n</robot>\n";
}

// What the call printed on standard output and standard error (file descriptors 1 and 2).
std::string consoleOf(const std::function<void()>& f) {
  const std::string file = (scratch() / "console.txt").string();
  std::fflush(stdout);
  std::fflush(stderr);
  const int out = ::dup(1), err = ::dup(2);
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  ::dup2(fd, 1);
  ::dup2(fd, 2);
  ::close(fd);
  try {
    f();
  } catch (...) {
  }
  std::fflush(stdout);
  std::fflush(stderr);
  ::dup2(out, 1);
  ::dup2(err, 2);
  ::close(out);
  ::close(err);
  return kccd::testing::readText(file);
}

}  // namespace

TEST(UrdfInputs, EveryMalformedCollisionIsAnError) {
  struct Case {
    std::string geometry, expected;
  };
  const Case cases[] = {
      {"<box size=\"1 1\"/>", "box size: 2 numbers, expected 3"},
      {"<sphere/>", "sphere radius: missing"},
      {"<sphere radius=\"abc\"/>", "sphere radius: 'abc' is not a number"},
      {"<sphere radius=\"-0.5\"/>", "sphere radius: -0.5 is negative"},
      {"<box size=\"1 -2 1\"/>", "box size: -2 is negative"},
      {"<cylinder radius=\"0.1\" length=\"1e999\"/>", "cylinder length: '1e999' is not a finite number"},
      {"<box size=\"1 nan 1\"/>", "'nan' is not a finite number"},
      {"<capsule radius=\"1\" length=\"1\"/>", "<capsule>: not a URDF shape"},
      {"", "<geometry> holds no shape"},
      {"<box size=\"1 1 1\"/><sphere radius=\"1\"/>", "<geometry> holds more than one shape"},
      {"<mesh filename=\"m.stl\" scale=\"1 0 1\"/>", "mesh scale: a factor of 0"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const std::string name = "collision" + std::to_string(i++) + ".urdf";
    const std::string message = urdfError(name, robotWith(c.geometry));
    EXPECT_NE(message.find(name + ":5: link 'a': collision 2: "), std::string::npos) << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
    expectOneLine(message, name);
  }
  const std::string origin = urdfError("origin.urdf",
                                       "<robot name=\"r\">\n<link name=\"a\"><collision>\n<origin xyz=\"0 0 inf\"/>"
                                       "<geometry><sphere radius=\"1\"/></geometry></collision></link>\n</robot>\n");
  EXPECT_NE(origin.find("origin.urdf:3: link 'a': collision 1: origin xyz: 'inf' is not a finite number"),
            std::string::npos)
      << origin;
}

TEST(UrdfInputs, UrdfdomPrintsNothingAndExplains) {
  const std::string path = write("limits.urdf",
                                 "<robot name=\"r\"><link name=\"a\"/><link name=\"b\"/>"
                                 "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>"
                                 "</joint></robot>");
  std::string message;
  const std::string console = consoleOf([&] { message = errorOf([&] { km::importUrdf(path); }); });
  EXPECT_EQ(console, "");
  EXPECT_NE(message.find("does not specify limits"), std::string::npos) << message;
  expectOneLine(message, "limits.urdf");
  EXPECT_EQ(consoleOf([&] { km::importUrdf(write("bad.urdf", robotWith("<box size=\"1 1\"/>"))); }), "");
}

TEST(UrdfInputs, OnlyRegularFiles) {
  EXPECT_NE(errorOf([] { km::importUrdf("/dev/zero"); }).find("/dev/zero: not a regular file"), std::string::npos);
  std::string deep = "<robot name=\"r\">";
  for (int i = 0; i < 5000; ++i) deep += "<a>";
  EXPECT_NE(urdfError("deep.urdf", deep).find("deep.urdf:1: malformed XML"), std::string::npos);
}
