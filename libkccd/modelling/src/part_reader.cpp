// Reading a rigid part with Coin3D: triangles of every shape in world (file) coordinates, and
// spheres, cylinders and cones covered analytically instead of by Coin's inscribed tessellation.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <Inventor/SbMatrix.h>
#include <Inventor/SoDB.h>
#include <Inventor/SoInput.h>
#include <Inventor/SoPrimitiveVertex.h>
#include <Inventor/VRMLnodes/SoVRMLBox.h>
#include <Inventor/VRMLnodes/SoVRMLCone.h>
#include <Inventor/VRMLnodes/SoVRMLCoordinate.h>
#include <Inventor/VRMLnodes/SoVRMLCylinder.h>
#include <Inventor/VRMLnodes/SoVRMLIndexedLine.h>
#include <Inventor/VRMLnodes/SoVRMLIndexedShape.h>
#include <Inventor/VRMLnodes/SoVRMLInline.h>
#include <Inventor/VRMLnodes/SoVRMLSphere.h>
#include <Inventor/actions/SoCallbackAction.h>
#include <Inventor/actions/SoSearchAction.h>
#include <Inventor/annex/ForeignFiles/SoForeignFileKit.h>
#include <Inventor/elements/SoCoordinateElement.h>
#include <Inventor/errors/SoDebugError.h>
#include <Inventor/errors/SoReadError.h>
#include <Inventor/misc/SoChildList.h>
#include <Inventor/nodekits/SoBaseKit.h>
#include <Inventor/nodekits/SoNodeKit.h>
#include <Inventor/nodes/SoArray.h>
#include <Inventor/nodes/SoCone.h>
#include <Inventor/nodes/SoCube.h>
#include <Inventor/nodes/SoCylinder.h>
#include <Inventor/nodes/SoFaceSet.h>
#include <Inventor/nodes/SoFile.h>
#include <Inventor/nodes/SoIndexedNurbsCurve.h>
#include <Inventor/nodes/SoIndexedNurbsSurface.h>
#include <Inventor/nodes/SoIndexedShape.h>
#include <Inventor/nodes/SoLineSet.h>
#include <Inventor/nodes/SoMultipleCopy.h>
#include <Inventor/nodes/SoNurbsCurve.h>
#include <Inventor/nodes/SoNurbsSurface.h>
#include <Inventor/nodes/SoPointSet.h>
#include <Inventor/nodes/SoQuadMesh.h>
#include <Inventor/nodes/SoScale.h>
#include <Inventor/nodes/SoSeparator.h>
#include <Inventor/nodes/SoShape.h>
#include <Inventor/nodes/SoSphere.h>
#include <Inventor/nodes/SoTriangleStripSet.h>
#include <Inventor/nodes/SoVertexProperty.h>
#include <Inventor/nodes/SoWWWInline.h>

#include "kccd/file_reader.hpp"
#include "kccd/format_number.hpp"
#include "kccd/model.hpp"
#include "kccd/modelling/part.hpp"
#include "large_stack.hpp"
#include "mesh_reader.hpp"
#include "part_messages.hpp"

namespace kccd::modelling {
namespace {

std::mutex coin_mutex;  // Coin's database and error handlers are process-wide

// Coin's reader and actions recurse once per nesting level. ASCII scenes are bounded before
// Coin sees them; a binary file can only be bounded by its size, so Coin runs on a large stack
// (detail::onLargeStack: about 28 bytes of binary file per level, well under 1 KiB of stack
// per level).

void initCoin() {
  static bool done = false;
  if (done) return;
  SoDB::init();
  SoNodeKit::init();
  SoForeignFileKit::initClass();
  done = true;
}

// The first message Coin posts through one error class, made one line. Coin's read errors end
// with "Occurred at line N in ...": the line is kept apart for the "file:line:" prefix.
struct Messages {
  std::string first;
  int line = 0;
  static void handler(const SoError* error, void* data) {
    auto* self = static_cast<Messages*>(data);
    if (!self->first.empty()) return;
    std::string s = error->getDebugString().getString();
    const std::size_t at = s.find("Occurred at line");
    if (at != std::string::npos) {
      self->line = std::atoi(s.c_str() + at + 16);
      s.erase(at);
    }
    for (const char* prefix : {"Coin read error: ", "Coin error in "})
      if (s.rfind(prefix, 0) == 0) s.erase(0, std::strlen(prefix));
    for (char& c : s)
      if (c == '\n' || c == '\t') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    if (s.find("non-valid floating point number") != std::string::npos)
      s = "a number is out of single-precision range";  // Coin would read it as 0
    self->first = printable(s, 300);
  }
  void clear() {
    first.clear();
    line = 0;
  }
};

Eigen::Affine3d toEigen(const SbMatrix& m) {
  // Coin uses row vectors: p' = p * M.
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) t.linear()(j, i) = m[i][j];
    t.translation()(i) = m[3][i];
  }
  return t;
}

// "Sphere" or "Sphere 'name'" (the DEF name), for messages.
std::string nodeName(const SoNode* node) {
  std::string label = node->getTypeId().getName().getString();
  const std::string name = node->getName().getString();
  if (!name.empty()) label += " '" + printable(name) + "'";
  return label;
}

struct Collector {
  Part part;
  std::string error;  // the first problem found: the traversal stops there
};

void triangle(void* data, SoCallbackAction* action, const SoPrimitiveVertex* v1, const SoPrimitiveVertex* v2,
              const SoPrimitiveVertex* v3) {
  auto* c = static_cast<Collector*>(data);
  const Eigen::Affine3d m = toEigen(action->getModelMatrix());
  auto at = [&](const SoPrimitiveVertex* v) {
    const SbVec3f& p = v->getPoint();
    return Vec3(m * Vec3(p[0], p[1], p[2]));
  };
  c->part.addTriangle(at(v1), at(v2), at(v3));
}

// A size of an analytic primitive: finite and not negative (zero is a degenerate but exact shape).
std::string checkSize(const char* field, double v) {
  if (!std::isfinite(v)) return std::string(field) + ": " + formatNumber(v, 9) + " is not finite";
  if (v < 0) return std::string(field) + ": " + formatNumber(v, 9) + " is negative";
  return {};
}

// Every index of `indices` is -1 (end of a face, line or strip) or one of `count` coordinates.
std::string checkIndices(const char* field, const SoMFInt32& indices, int count) {
  const int32_t* v = indices.getValues(0);
  for (int i = 0; i < indices.getNum(); ++i)
    if (v[i] < -1 || v[i] >= count)
      return std::string(field) + "[" + std::to_string(i) + "]: " + std::to_string(v[i]) +
             " is not a coordinate index (" + std::to_string(count) + " coordinates)";
  return {};
}

// start + the vertices counts (-1: all the rest) within `count` coordinates, each count at least
// `least` (Coin reads out of bounds or allocates without end on a face or strip of fewer than 3).
std::string checkCounts(const SoMFInt32& counts, int start, int count, int least = 0) {
  if (start < 0 || start > count)
    return "startIndex: " + std::to_string(start) + " is outside the " + std::to_string(count) + " coordinates";
  long long used = start;
  for (int i = 0; i < counts.getNum(); ++i) {
    const int32_t n = counts[i];
    if (n == -1 && i + 1 == counts.getNum()) {
      if (count - used < least)
        return "numVertices[" + std::to_string(i) + "]: -1 (the rest) leaves " + std::to_string(count - used) +
               " vertices, fewer than " + std::to_string(least);
      break;
    }
    if (n < 0) return "numVertices[" + std::to_string(i) + "]: " + std::to_string(n) + " is negative";
    if (n < least)
      return "numVertices[" + std::to_string(i) + "]: " + std::to_string(n) + " vertices, at least " +
             std::to_string(least) + " needed";
    used += n;
    if (used > count)
      return "numVertices: " + std::to_string(used - start) + " vertices from index " + std::to_string(start) +
             " but only " + std::to_string(count) + " coordinates";
  }
  return {};
}

int vrmlCoordinates(const SoSFNode& coord) {
  const SoNode* node = coord.getValue();
  if (!node || !node->isOfType(SoVRMLCoordinate::getClassTypeId())) return 0;
  return static_cast<const SoVRMLCoordinate*>(node)->point.getNum();
}

int inventorCoordinates(SoCallbackAction* action, const SoVertexShape* shape) {
  const SoNode* vp = shape->vertexProperty.getValue();
  if (vp && vp->isOfType(SoVertexProperty::getClassTypeId())) {
    const int n = static_cast<const SoVertexProperty*>(vp)->vertex.getNum();
    if (n > 0) return n;
  }
  return action->getNumCoordinates();
}

// Checks one shape before Coin generates its triangles; spheres, cylinders and cones are covered
// here analytically (PRUNE: no inscribed tessellation).
SoCallbackAction::Response shape(void* data, SoCallbackAction* action, const SoNode* node) {
  auto* c = static_cast<Collector*>(data);
  const SbMatrix& matrix = action->getModelMatrix();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      if (!std::isfinite(matrix[i][j])) {
        c->error = nodeName(node) + ": its transform is not finite (a scale, rotation or translation overflows)";
        return SoCallbackAction::ABORT;
      }
  const Eigen::Affine3d m = toEigen(matrix);
  std::string problem;
  SoCallbackAction::Response response = SoCallbackAction::CONTINUE;
  auto first = [&](std::initializer_list<std::string> checks) {
    for (const std::string& p : checks)
      if (!p.empty()) {
        problem = p;
        return false;
      }
    return true;
  };
  if (node->isOfType(SoSphere::getClassTypeId()) || node->isOfType(SoVRMLSphere::getClassTypeId())) {
    const double r = node->isOfType(SoVRMLSphere::getClassTypeId())
                         ? static_cast<const SoVRMLSphere*>(node)->radius.getValue()
                         : static_cast<const SoSphere*>(node)->radius.getValue();
    if (first({checkSize("radius", r)})) c->part.addSphere(m, r);
    response = SoCallbackAction::PRUNE;
  } else if (node->isOfType(SoCylinder::getClassTypeId()) || node->isOfType(SoVRMLCylinder::getClassTypeId())) {
    double r, h;
    if (node->isOfType(SoVRMLCylinder::getClassTypeId())) {
      r = static_cast<const SoVRMLCylinder*>(node)->radius.getValue();
      h = static_cast<const SoVRMLCylinder*>(node)->height.getValue();
    } else {
      r = static_cast<const SoCylinder*>(node)->radius.getValue();
      h = static_cast<const SoCylinder*>(node)->height.getValue();
    }
    if (first({checkSize("radius", r), checkSize("height", h)})) c->part.addCylinderY(m, r, h);
    response = SoCallbackAction::PRUNE;
  } else if (node->isOfType(SoCone::getClassTypeId()) || node->isOfType(SoVRMLCone::getClassTypeId())) {
    double r, h;
    if (node->isOfType(SoVRMLCone::getClassTypeId())) {
      r = static_cast<const SoVRMLCone*>(node)->bottomRadius.getValue();
      h = static_cast<const SoVRMLCone*>(node)->height.getValue();
    } else {
      r = static_cast<const SoCone*>(node)->bottomRadius.getValue();
      h = static_cast<const SoCone*>(node)->height.getValue();
    }
    if (first({checkSize("bottomRadius", r), checkSize("height", h)})) c->part.addConeY(m, r, h);
    response = SoCallbackAction::PRUNE;
  } else if (node->isOfType(SoCube::getClassTypeId())) {
    const auto* cube = static_cast<const SoCube*>(node);
    first({checkSize("width", cube->width.getValue()), checkSize("height", cube->height.getValue()),
           checkSize("depth", cube->depth.getValue())});
  } else if (node->isOfType(SoVRMLBox::getClassTypeId())) {
    const SbVec3f size = static_cast<const SoVRMLBox*>(node)->size.getValue();
    first({checkSize("size x", size[0]), checkSize("size y", size[1]), checkSize("size z", size[2])});
  } else if (node->isOfType(SoIndexedShape::getClassTypeId())) {
    const auto* s = static_cast<const SoIndexedShape*>(node);
    first({checkIndices("coordIndex", s->coordIndex, inventorCoordinates(action, s))});
  } else if (node->isOfType(SoFaceSet::getClassTypeId()) || node->isOfType(SoLineSet::getClassTypeId()) ||
             node->isOfType(SoTriangleStripSet::getClassTypeId())) {
    const auto* s = static_cast<const SoNonIndexedShape*>(node);
    const SoMFInt32& counts =
        node->isOfType(SoFaceSet::getClassTypeId())   ? static_cast<const SoFaceSet*>(node)->numVertices
        : node->isOfType(SoLineSet::getClassTypeId()) ? static_cast<const SoLineSet*>(node)->numVertices
                                                      : static_cast<const SoTriangleStripSet*>(node)->numVertices;
    const int least = node->isOfType(SoLineSet::getClassTypeId()) ? 2 : 3;
    first({checkCounts(counts, s->startIndex.getValue(), inventorCoordinates(action, s), least)});
  } else if (node->isOfType(SoPointSet::getClassTypeId())) {
    const auto* s = static_cast<const SoPointSet*>(node);
    SoMFInt32 counts;
    counts.setValue(s->numPoints.getValue());
    first({checkCounts(counts, s->startIndex.getValue(), inventorCoordinates(action, s))});
  } else if (node->isOfType(SoQuadMesh::getClassTypeId())) {
    const auto* s = static_cast<const SoQuadMesh*>(node);
    const long long rows = s->verticesPerColumn.getValue(), columns = s->verticesPerRow.getValue();
    const int count = inventorCoordinates(action, s);
    if (rows < 0 || columns < 0 || s->startIndex.getValue() < 0 || s->startIndex.getValue() + rows * columns > count)
      problem = "verticesPerColumn x verticesPerRow: " + std::to_string(rows) + " x " + std::to_string(columns) +
                " vertices from index " + std::to_string(s->startIndex.getValue()) + " but only " +
                std::to_string(count) + " coordinates";
  } else if (node->isOfType(SoNurbsSurface::getClassTypeId()) ||
             node->isOfType(SoIndexedNurbsSurface::getClassTypeId())) {
    // Coin tessellates NURBS with GLU, which needs an OpenGL context (a crash without a display).
    // A NURBS surface with positive weights lies in the convex hull of its control points:
    // they are its cover.
    const SoCoordinateElement* coords = SoCoordinateElement::getInstance(action->getState());
    const int count = coords->getNum();
    std::vector<int> used;
    if (node->isOfType(SoNurbsSurface::getClassTypeId())) {
      const auto* s = static_cast<const SoNurbsSurface*>(node);
      const long long n = static_cast<long long>(s->numUControlPoints.getValue()) * s->numVControlPoints.getValue();
      if (s->numUControlPoints.getValue() < 0 || s->numVControlPoints.getValue() < 0 || n > count)
        problem = "numUControlPoints x numVControlPoints: " + std::to_string(s->numUControlPoints.getValue()) + " x " +
                  std::to_string(s->numVControlPoints.getValue()) + " but only " + std::to_string(count) +
                  " coordinates";
      else
        for (int i = 0; i < n; ++i) used.push_back(i);
    } else {
      const auto* s = static_cast<const SoIndexedNurbsSurface*>(node);
      if (first({checkIndices("coordIndex", s->coordIndex, count)}))
        for (int i = 0; i < s->coordIndex.getNum(); ++i)
          if (s->coordIndex[i] >= 0) used.push_back(s->coordIndex[i]);
    }
    for (const int i : used) {
      if (!problem.empty()) break;
      if (coords->is3D()) {
        const SbVec3f& p = coords->get3(i);
        c->part.points.push_back(m * Vec3(p[0], p[1], p[2]));
      } else {
        const SbVec4f& p = coords->get4(i);
        if (!(p[3] > 0))
          problem = "control point " + std::to_string(i) + ": weight " + formatNumber(p[3], 9) + " is not positive";
        else
          c->part.points.push_back(m * (Vec3(p[0], p[1], p[2]) / p[3]));
      }
    }
    ++c->part.primitives;
    response = SoCallbackAction::PRUNE;
  } else if (node->isOfType(SoNurbsCurve::getClassTypeId()) || node->isOfType(SoIndexedNurbsCurve::getClassTypeId())) {
    response = SoCallbackAction::PRUNE;  // a curve has no volume (like line sets); GLU would need OpenGL
  } else if (node->isOfType(SoVRMLIndexedShape::getClassTypeId())) {
    const auto* s = static_cast<const SoVRMLIndexedShape*>(node);
    first({checkIndices("coordIndex", s->coordIndex, vrmlCoordinates(s->coord))});
  } else if (node->isOfType(SoVRMLIndexedLine::getClassTypeId())) {
    const auto* s = static_cast<const SoVRMLIndexedLine*>(node);
    first({checkIndices("coordIndex", s->coordIndex, vrmlCoordinates(s->coord))});
  }
  if (!problem.empty()) {
    c->error = nodeName(node) + ": " + problem;
    return SoCallbackAction::ABORT;
  }
  return response;
}

void collect(Collector& c, SoNode* node, SoPath* path) {
  SoCallbackAction action;
  action.addTriangleCallback(SoShape::getClassTypeId(), triangle, &c);
  action.addPreCallback(SoShape::getClassTypeId(), shape, &c);
  if (path)
    action.apply(path);
  else
    action.apply(node);
}

std::string nodeLabel(SoNode* node, int index) {
  const std::string name = node->getName().getString();
  if (!name.empty()) return printable(name);
  std::string label = "#";
  label += std::to_string(index + 1);
  label += " (";
  label += node->getTypeId().getName().getString();
  label += ")";
  return label;
}

// STL, ASCII or binary: a list of triangles (binary when the size matches its triangle count).
// Read here rather than through Assimp, whose STL reader leaks memory on malformed files (seen
// by fuzz_part: 4.7 MB over 4,000 inputs; none with this reader).
Part readStl(const std::string& data, const std::string& path, const Vec3& scale) {
  Part part;
  auto add = [&](const Vec3& v) { part.points.push_back(v.cwiseProduct(scale)); };
  std::uint32_t count = 0;
  if (data.size() >= 84) std::memcpy(&count, data.data() + 80, 4);
  if (data.size() >= 84 && data.size() == 84 + 50ull * count) {
    for (std::uint32_t t = 0; t < count; ++t) {
      const char* rec = data.data() + 84 + 50ull * t + 12;  // skip the normal
      Vec3 corner[3];
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 * k, 12);
        corner[k] = Vec3(xyz[0], xyz[1], xyz[2]).cwiseProduct(scale);
      }
      part.addTriangle(corner[0], corner[1], corner[2]);
    }
  } else {
    if (data.compare(0, 5, "solid") != 0)
      throw PartError(path + ": not an STL file (neither ASCII 'solid' nor a binary triangle count)");
    std::istringstream text(data);
    std::string word;
    int line_vertices = 0;
    std::size_t line = 1, counted = 0;  // the line of the text's position `counted`
    const auto lineAt = [&](std::streamoff at) {
      // tellg() is -1 once the stream hit the end: the line of the text's end then.
      const auto end = std::max(counted, at < 0 ? data.size() : static_cast<std::size_t>(at));
      line += static_cast<std::size_t>(
          std::count(data.begin() + static_cast<std::ptrdiff_t>(counted),
                     data.begin() + static_cast<std::ptrdiff_t>(std::min(end, data.size())), '\n'));
      counted = std::max(counted, std::min(end, data.size()));
      return line;
    };
    while (text >> word) {
      if (word != "vertex") continue;
      const std::size_t at = lineAt(text.tellg());
      Vec3 v;
      if (!(text >> v.x() >> v.y() >> v.z()))
        throw PartError(InputLocation{path, at, 0, "vertex " + std::to_string(part.points.size() + 1)},
                        "malformed (three numbers expected)");
      const Vec3 scaled = v.cwiseProduct(scale);
      if (!scaled.allFinite() || scaled.cwiseAbs().maxCoeff() > kMaxModelLength)
        throw PartError(InputLocation{path, at, 0, "vertex " + std::to_string(part.points.size() + 1)},
                        formatNumber(v.x(), 9) + " " + formatNumber(v.y(), 9) + " " + formatNumber(v.z(), 9) +
                            (scale == Vec3::Ones() ? "" : " (scaled)") +
                            " is beyond the largest length a model may give (1e6 m)");
      add(v);
      if (++line_vertices % 3 == 0) {
        const int n = static_cast<int>(part.points.size());
        part.faces.push_back({n - 3, n - 2, n - 1});
        ++part.triangles;
      }
    }
    if (line_vertices % 3 != 0) throw PartError(path + ": truncated facet (vertex count not a multiple of 3)");
  }
  return part;
}

// An ASCII Open Inventor or VRML text before Coin reads it: nesting of braces and brackets
// (outside strings and comments) at most kMaxNesting, and no node that includes another file.
constexpr std::size_t kMaxWordBytes = 4096;

void scanText(const std::string& data, const std::string& path) {
  int depth = 0, line = 1;
  std::string token, previous;
  auto endToken = [&] {
    if (token.empty()) return;
    static const char* const includes[] = {"File",         "SoFile",    "Inline",      "VRMLInline",
                                           "SoVRMLInline", "WWWInline", "SoWWWInline", "EXTERNPROTO"};
    if (previous != "DEF" && previous != "USE" && previous != "PROTO")
      for (const char* include : includes)
        if (token == include)
          throw PartError(path + ":" + std::to_string(line) + ": " + token +
                          ": includes are not supported (put the included geometry into this file)");
    previous = std::move(token);
    token.clear();
  };
  for (std::size_t i = 0; i < data.size(); ++i) {
    const char ch = data[i];
    if (ch == '#') {  // a comment (the header too) to the end of the line
      endToken();
      while (i + 1 < data.size() && data[i + 1] != '\n' && data[i + 1] != '\r') ++i;
    } else if (ch == '"') {
      endToken();
      const int start = line;
      for (++i; i < data.size() && data[i] != '"'; ++i) {
        if (data[i] == '\\') ++i;
        if (i < data.size() && data[i] == '\n') ++line;
      }
      if (i >= data.size()) throw PartError(path + ":" + std::to_string(start) + ": unterminated string");
      previous.assign(1, '"');
    } else if (ch == '{' || ch == '[') {
      endToken();
      if (++depth > kMaxNesting)
        throw PartError(path + ":" + std::to_string(line) + ": nested deeper than " + std::to_string(kMaxNesting) +
                        " levels");
      previous.assign(1, ch);
    } else if (ch == '}' || ch == ']') {
      endToken();
      if (--depth < 0) throw PartError(path + ":" + std::to_string(line) + ": '" + ch + "' closes nothing");
      previous.assign(1, ch);
    } else if (std::isspace(static_cast<unsigned char>(ch)) || ch == ',') {
      endToken();
      if (ch == '\n') ++line;
    } else {
      // Coin's reader crashes (a double free) on a word of about a megabyte (found by the
      // reader-bound test); names and numbers are short.
      if (token.size() >= kMaxWordBytes)
        throw PartError(path + ":" + std::to_string(line) + ": a word longer than " + std::to_string(kMaxWordBytes) +
                        " bytes ('" + kccd::printable(token, 20) + "')");
      token += ch;
    }
  }
  endToken();
}

struct RefGuard {
  SoNode* node;
  explicit RefGuard(SoNode* n) : node(n) { node->ref(); }
  ~RefGuard() { node->unref(); }
};

// Group nesting of a scene, without recursion, and the nodes a traversal visits: a node used
// again (DEF/USE) is visited once per use and an Array or MultipleCopy visits its children once
// per copy, so a few hundred bytes can stand for 10^10 visits of every later action. Both are
// bounded before any action runs.
void checkNesting(SoNode* root, const std::string& path) {
  constexpr double kMaxVisits = 1e6;
  struct Entry {
    SoNode* node;
    int depth;
    double copies;  // visits of this node per traversal
  };
  std::vector<Entry> stack{{root, 0, 1.0}};
  double visits = 0.0;
  while (!stack.empty()) {
    const Entry e = stack.back();
    stack.pop_back();
    if (e.depth > kMaxNesting)
      throw PartError(path + ": nested deeper than " + std::to_string(kMaxNesting) + " levels");
    visits += e.copies;
    if (visits > kMaxVisits)
      throw PartError(path +
                      ": the scene expands to more than 1000000 nodes (nodes used again with USE, or Array and "
                      "MultipleCopy nodes, multiply): write the geometry out");
    // Groups and node kits alike: every node with children (a kit's parts are traversed too).
    const SoChildList* children = e.node->getChildren();
    if (!children) continue;
    double copies = e.copies;
    if (e.node->isOfType(SoArray::getClassTypeId())) {
      const auto* array = static_cast<SoArray*>(e.node);
      copies *= std::max(1.0, static_cast<double>(array->numElements1.getValue())) *
                std::max(1.0, static_cast<double>(array->numElements2.getValue())) *
                std::max(1.0, static_cast<double>(array->numElements3.getValue()));
    } else if (e.node->isOfType(SoMultipleCopy::getClassTypeId())) {
      copies *= std::max(1, static_cast<SoMultipleCopy*>(e.node)->matrix.getNum());
    }
    for (int i = 0; i < children->getLength(); ++i) stack.push_back({(*children)[i], e.depth + 1, copies});
  }
}

// Nodes that include other files are refused, whatever the pre-checks above missed (Inline nodes
// are never fetched: without this check their geometry would be missing silently).
void checkIncludes(SoNode* root, const std::string& path) {
  for (const SoType type : {SoFile::getClassTypeId(), SoVRMLInline::getClassTypeId(), SoWWWInline::getClassTypeId()}) {
    SoSearchAction search;
    search.setType(type);
    search.setInterest(SoSearchAction::FIRST);
    search.setSearchingAll(TRUE);
    search.apply(root);
    if (!search.getPath()) continue;
    const SoNode* node = search.getPath()->getTail();
    std::string target;
    if (node->isOfType(SoFile::getClassTypeId()))
      target = static_cast<const SoFile*>(node)->name.getValue().getString();
    else if (node->isOfType(SoVRMLInline::getClassTypeId()) && static_cast<const SoVRMLInline*>(node)->url.getNum() > 0)
      target = static_cast<const SoVRMLInline*>(node)->url[0].getString();
    else if (node->isOfType(SoWWWInline::getClassTypeId()))
      target = static_cast<const SoWWWInline*>(node)->name.getValue().getString();
    throw PartError(path + ": " + nodeName(node) + " '" + printable(target) +
                    "': includes are not supported (put the included geometry into this file)");
  }
}

// Any scene Coin reads (Open Inventor, VRML), with the part selection of `options`.
Part readScene(const std::string& data, const std::string& path, const ReadOptions& options) {
  const std::string header = data.substr(0, data.find('\n'));
  if (header.rfind("#Inventor", 0) != 0 && header.rfind("#VRML", 0) != 0)
    throw PartError(path + ": not a readable Open Inventor, VRML or STL file (no #Inventor or #VRML header)");
  const bool binary = header.find("binary") != std::string::npos;
  if (binary && data.size() > kMaxBinaryInventorBytes)
    throw PartError(path + ": binary Open Inventor files are read up to " +
                    std::to_string(kMaxBinaryInventorBytes >> 20) + " MiB (this one has " +
                    std::to_string(data.size()) + " bytes): convert it to ASCII");
  if (!binary) scanText(data, path);
  // Binary files name node types as length-prefixed strings: a File node would be read by Coin
  // (following cycles, devices and missing files) before any check of the scene.
  for (const std::string_view file : {std::string_view("\0\0\0\4File", 8), std::string_view("\0\0\0\6SoFile", 10)})
    if (binary && data.find(file) != std::string::npos)
      throw PartError(path + ": File node at byte " + std::to_string(data.find(file)) +
                      ": includes are not supported (put the included geometry into this file)");

  std::lock_guard<std::mutex> lock(coin_mutex);
  Part result;
  detail::onLargeStack([&] {
    initCoin();
    // Coin keeps the handlers' data pointers: they must outlive the call.
    static Messages read_errors, other_errors;
    read_errors.clear();
    other_errors.clear();
    SoReadError::setHandlerCallback(&Messages::handler, &read_errors);
    SoDebugError::setHandlerCallback(&Messages::handler, &other_errors);

    SoInput input;
    input.setBuffer(data.data(), data.size());
    // Node by node: SoDB::readAll would hand back a lone top-level separator itself, hiding
    // whether the file holds one part or several.
    SoSeparator* root = new SoSeparator;
    root->ref();
    bool ok = true;
    for (;;) {
      SoNode* node = nullptr;
      if (!SoDB::read(&input, node)) {
        ok = false;
        break;
      }
      if (!node) break;  // end of file
      root->addChild(node);
    }
    // Coin reports some problems and reads on (an overflowing number becomes 0): any read error
    // refuses the file, whose model would differ from its text.
    if (!read_errors.first.empty()) {
      root->unref();
      throw PartError(path + (read_errors.line > 0 ? ":" + std::to_string(read_errors.line) : "") + ": " +
                      read_errors.first);
    }
    if (!ok || (root->getNumChildren() == 0 && !other_errors.first.empty())) {
      root->unref();
      throw PartError(path + ": not a readable Open Inventor, VRML or STL file" +
                      (other_errors.first.empty() ? std::string() : " (" + other_errors.first + ")"));
    }
    root->unrefNoDelete();
    RefGuard keep(root);
    checkNesting(root, path);
    checkIncludes(root, path);
    SoBaseKit::setSearchingChildren(TRUE);

    SoSeparator* top = root;
    if (options.scale != Vec3::Ones()) {
      top = new SoSeparator;
      auto* scale = new SoScale;
      scale->scaleFactor.setValue(static_cast<float>(options.scale.x()), static_cast<float>(options.scale.y()),
                                  static_cast<float>(options.scale.z()));
      top->addChild(scale);
      top->addChild(root);
    }
    RefGuard keep_top(top);

    Collector c;
    auto run = [&](Collector& into, SoNode* node, SoPath* p) {
      collect(into, node, p);
      if (!into.error.empty()) throw PartError(path + ": " + into.error);
    };
    if (!options.part.empty()) {
      SoSearchAction search;
      search.setName(SbName(options.part.c_str()));
      search.setInterest(SoSearchAction::FIRST);
      search.setSearchingAll(TRUE);
      search.apply(top);
      SoPath* found = search.getPath();
      if (!found)
        throw PartError(path + ": no node named '" + printable(options.part) + "' (DEF " + printable(options.part) +
                        ")");
      SoPath* copy = found->copy();
      copy->ref();
      try {
        run(c, nullptr, copy);
      } catch (...) {
        copy->unref();
        throw;
      }
      copy->unref();
    } else {
      // Count the top-level parts that hold geometry: several of them is more than one body.
      std::vector<std::string> parts;
      // Each through a path from the root: top-level nodes to its left set the state it uses
      // (a Coordinate3 before an IndexedFaceSet).
      for (int i = 0; i < root->getNumChildren(); ++i) {
        Collector probe;
        SoPath* to_child = new SoPath(root);
        to_child->ref();
        to_child->append(i);
        try {
          run(probe, nullptr, to_child);
        } catch (...) {
          to_child->unref();
          throw;
        }
        to_child->unref();
        if (!probe.part.empty()) parts.push_back(nodeLabel(root->getChild(i), i));
      }
      if (parts.size() > 1 && !options.merge) {
        throw detail::severalParts(path, parts);
      }
      run(c, top, nullptr);
    }
    result = std::move(c.part);
  });
  return result;
}

}  // namespace

std::string readInputFile(const std::string& path, std::uintmax_t max_bytes) {
  try {
    return readRegularFile(path, max_bytes);
  } catch (const FileError& e) {
    throw InputError(e.location(), e.problem());
  }
}

Part readPart(const std::string& path, const ReadOptions& options) {
  const std::string name = printable(path, 1024);
  if (!options.scale.allFinite() || (options.scale.array() == 0.0).any())
    throw PartError(name + ": scale " + formatNumber(options.scale.x(), 9) + " " + formatNumber(options.scale.y(), 9) +
                    " " + formatNumber(options.scale.z(), 9) + ": factors must be finite and non-zero");
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  const std::string data = readInputFile(path);
  // STL directly; Open Inventor and VRML (analytic primitives, scene graphs) through Coin3D;
  // other meshes (OBJ, COLLADA, PLY, glTF, ...) through Assimp.
  Part part = extension == ".stl"              ? readStl(data, name, options.scale)
              : detail::readsAsMesh(extension) ? detail::readMesh(data, path, name, extension, options)
                                               : readScene(data, name, options);
  if (part.triangles == 0 && part.primitives == 0)
    throw PartError(name + (options.part.empty() ? "" : " (part " + printable(options.part) + ")") +
                    ": no triangles or solid primitives (nothing to fit)");
  // Every coordinate within what a model may hold (the fit's distances stay finite then).
  for (std::size_t i = 0; i < part.points.size(); ++i) {
    const Vec3& p = part.points[i];
    if (!p.allFinite()) throw PartError(name + ": vertex " + std::to_string(i + 1) + ": non-finite coordinates");
    if (p.cwiseAbs().maxCoeff() > kMaxModelLength)
      throw PartError(name + ": vertex " + std::to_string(i + 1) + ": " + formatNumber(p.x(), 9) + " " +
                      formatNumber(p.y(), 9) + " " + formatNumber(p.z(), 9) +
                      " is beyond the largest length a model may give (1e6 m)");
  }
  for (const Sphere& b : part.balls) {
    if (!b.center.allFinite() || !std::isfinite(b.radius))
      throw PartError(name + ": non-finite sphere (a scale or radius overflows)");
    if (b.center.cwiseAbs().maxCoeff() + b.radius > kMaxModelLength)
      throw PartError(name + ": a sphere of radius " + formatNumber(b.radius, 9) +
                      " reaches beyond the largest length a model may give (1e6 m)");
  }
  double max_abs = 0.0;
  for (const Vec3& p : part.points) max_abs = std::max(max_abs, p.cwiseAbs().maxCoeff());
  for (const Sphere& b : part.balls) max_abs = std::max(max_abs, b.center.cwiseAbs().maxCoeff() + b.radius);
  // Coin and STL store single-precision coordinates (Coin its matrices too): cover their rounding.
  part.coordinate_guard = 1e-6 * max_abs;
  if (!std::isfinite(part.coordinate_guard)) throw PartError(name + ": coordinates too large (their extent overflows)");
  return part;
}

}  // namespace kccd::modelling
