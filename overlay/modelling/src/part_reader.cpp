// Reading a rigid part with Coin3D: triangles of every shape in world (file) coordinates, and
// spheres, cylinders and cones covered analytically instead of by Coin's inscribed tessellation.
#include <cctype>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <stdexcept>

#include <Inventor/SbMatrix.h>
#include <Inventor/SoDB.h>
#include <Inventor/SoInput.h>
#include <Inventor/SoPrimitiveVertex.h>
#include <Inventor/VRMLnodes/SoVRMLCone.h>
#include <Inventor/VRMLnodes/SoVRMLCylinder.h>
#include <Inventor/VRMLnodes/SoVRMLSphere.h>
#include <Inventor/actions/SoCallbackAction.h>
#include <Inventor/actions/SoSearchAction.h>
#include <Inventor/annex/ForeignFiles/SoForeignFileKit.h>
#include <Inventor/errors/SoDebugError.h>
#include <Inventor/errors/SoReadError.h>
#include <Inventor/nodekits/SoBaseKit.h>
#include <Inventor/nodekits/SoNodeKit.h>
#include <Inventor/nodes/SoCone.h>
#include <Inventor/nodes/SoCylinder.h>
#include <Inventor/nodes/SoScale.h>
#include <Inventor/nodes/SoSeparator.h>
#include <Inventor/nodes/SoShape.h>
#include <Inventor/nodes/SoSphere.h>

#include "kccd/modelling/part.hpp"

namespace kccd::modelling {
namespace {

std::mutex coin_mutex;  // Coin's database and error handlers are process-wide

void initCoin() {
  static bool done = false;
  if (done) return;
  SoDB::init();
  SoNodeKit::init();
  SoForeignFileKit::initClass();
  done = true;
}

struct Messages {
  std::string first;
  static void handler(const SoError* error, void* data) {
    auto* self = static_cast<Messages*>(data);
    if (self->first.empty()) {
      std::string s = error->getDebugString().getString();
      for (char& c : s)
        if (c == '\n') c = ' ';
      self->first = s;
    }
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

struct Collector {
  Part part;
};

void triangle(void* data, SoCallbackAction* action, const SoPrimitiveVertex* v1, const SoPrimitiveVertex* v2,
              const SoPrimitiveVertex* v3) {
  auto* c = static_cast<Collector*>(data);
  const Eigen::Affine3d m = toEigen(action->getModelMatrix());
  for (const SoPrimitiveVertex* v : {v1, v2, v3}) {
    const SbVec3f& p = v->getPoint();
    c->part.points.push_back(m * Vec3(p[0], p[1], p[2]));
  }
  ++c->part.triangles;
}

SoCallbackAction::Response sphere(void* data, SoCallbackAction* action, const SoNode* node) {
  auto* c = static_cast<Collector*>(data);
  const double r = node->isOfType(SoVRMLSphere::getClassTypeId())
                       ? static_cast<const SoVRMLSphere*>(node)->radius.getValue()
                       : static_cast<const SoSphere*>(node)->radius.getValue();
  c->part.addSphere(toEigen(action->getModelMatrix()), r);
  return SoCallbackAction::PRUNE;
}

SoCallbackAction::Response cylinder(void* data, SoCallbackAction* action, const SoNode* node) {
  auto* c = static_cast<Collector*>(data);
  double r, h;
  if (node->isOfType(SoVRMLCylinder::getClassTypeId())) {
    r = static_cast<const SoVRMLCylinder*>(node)->radius.getValue();
    h = static_cast<const SoVRMLCylinder*>(node)->height.getValue();
  } else {
    r = static_cast<const SoCylinder*>(node)->radius.getValue();
    h = static_cast<const SoCylinder*>(node)->height.getValue();
  }
  c->part.addCylinderY(toEigen(action->getModelMatrix()), r, h);
  return SoCallbackAction::PRUNE;
}

SoCallbackAction::Response cone(void* data, SoCallbackAction* action, const SoNode* node) {
  auto* c = static_cast<Collector*>(data);
  double r, h;
  if (node->isOfType(SoVRMLCone::getClassTypeId())) {
    r = static_cast<const SoVRMLCone*>(node)->bottomRadius.getValue();
    h = static_cast<const SoVRMLCone*>(node)->height.getValue();
  } else {
    r = static_cast<const SoCone*>(node)->bottomRadius.getValue();
    h = static_cast<const SoCone*>(node)->height.getValue();
  }
  c->part.addConeY(toEigen(action->getModelMatrix()), r, h);
  return SoCallbackAction::PRUNE;
}

void collect(Collector& c, SoNode* node, SoPath* path) {
  SoCallbackAction action;
  action.addTriangleCallback(SoShape::getClassTypeId(), triangle, &c);
  action.addPreCallback(SoSphere::getClassTypeId(), sphere, &c);
  action.addPreCallback(SoVRMLSphere::getClassTypeId(), sphere, &c);
  action.addPreCallback(SoCylinder::getClassTypeId(), cylinder, &c);
  action.addPreCallback(SoVRMLCylinder::getClassTypeId(), cylinder, &c);
  action.addPreCallback(SoCone::getClassTypeId(), cone, &c);
  action.addPreCallback(SoVRMLCone::getClassTypeId(), cone, &c);
  if (path)
    action.apply(path);
  else
    action.apply(node);
}

std::string nodeLabel(SoNode* node, int index) {
  const std::string name = node->getName().getString();
  if (!name.empty()) return name;
  std::string label = "#";
  label += std::to_string(index + 1);
  label += " (";
  label += node->getTypeId().getName().getString();
  label += ")";
  return label;
}

// STL, ASCII or binary: a list of triangles (binary when the size matches its triangle count).
Part readStl(const std::string& path, const Vec3& scale) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the file");
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Part part;
  auto add = [&](const Vec3& v) { part.points.push_back(v.cwiseProduct(scale)); };
  std::uint32_t count = 0;
  if (data.size() >= 84) std::memcpy(&count, data.data() + 80, 4);
  if (data.size() >= 84 && data.size() == 84 + 50ull * count) {
    for (std::uint32_t t = 0; t < count; ++t) {
      const char* rec = data.data() + 84 + 50ull * t + 12;  // skip the normal
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 * k, 12);
        add(Vec3(xyz[0], xyz[1], xyz[2]));
      }
    }
    part.triangles = static_cast<int>(count);
  } else {
    if (data.compare(0, 5, "solid") != 0)
      throw std::runtime_error(path + ": not an STL file (neither ASCII 'solid' nor a binary triangle count)");
    std::istringstream text(data);
    std::string word;
    int line_vertices = 0;
    while (text >> word) {
      if (word != "vertex") continue;
      Vec3 v;
      if (!(text >> v.x() >> v.y() >> v.z()))
        throw std::runtime_error(path + ": malformed vertex after " + std::to_string(part.points.size()) +
                                 " vertices");
      add(v);
      if (++line_vertices % 3 == 0) ++part.triangles;
    }
    if (line_vertices % 3 != 0) throw std::runtime_error(path + ": truncated facet (vertex count not a multiple of 3)");
  }
  return part;
}

struct RefGuard {
  SoNode* node;
  explicit RefGuard(SoNode* n) : node(n) { node->ref(); }
  ~RefGuard() { node->unref(); }
};

// Any scene Coin reads (Open Inventor, VRML), with the part selection of `options`.
Part readScene(const std::string& path, const ReadOptions& options) {
  std::lock_guard<std::mutex> lock(coin_mutex);
  initCoin();
  static Messages messages;  // Coin keeps the handler's data pointer: it must outlive the call
  messages.first.clear();
  SoReadError::setHandlerCallback(&Messages::handler, &messages);
  SoDebugError::setHandlerCallback(&Messages::handler, &messages);

  SoInput input;
  if (!input.openFile(path.c_str(), TRUE)) throw std::runtime_error(path + ": cannot open the file");
  SoSeparator* root = nullptr;
  // Node by node: SoDB::readAll would hand back a lone top-level separator itself, hiding
  // whether the file holds one part or several.
  root = new SoSeparator;
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
  input.closeFile();
  if (!ok || (root->getNumChildren() == 0 && !messages.first.empty())) {
    root->unref();
    root = nullptr;
  } else {
    root->unrefNoDelete();
  }
  if (!root)
    throw std::runtime_error(path + ": not a readable Open Inventor, VRML or STL file" +
                             (messages.first.empty() ? std::string() : " (" + messages.first + ")"));
  RefGuard keep(root);
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
  if (!options.part.empty()) {
    SoSearchAction search;
    search.setName(SbName(options.part.c_str()));
    search.setInterest(SoSearchAction::FIRST);
    search.setSearchingAll(TRUE);
    search.apply(top);
    SoPath* found = search.getPath();
    if (!found) throw std::runtime_error(path + ": no node named '" + options.part + "' (DEF " + options.part + ")");
    SoPath* copy = found->copy();
    copy->ref();
    collect(c, nullptr, copy);
    copy->unref();
  } else {
    // Count the top-level parts that hold geometry: several of them is more than one body.
    std::vector<std::string> parts;
    for (int i = 0; i < root->getNumChildren(); ++i) {
      Collector probe;
      collect(probe, root->getChild(i), nullptr);
      if (!probe.part.empty()) parts.push_back(nodeLabel(root->getChild(i), i));
    }
    if (parts.size() > 1 && !options.merge) {
      std::string list;
      for (std::size_t i = 0; i < parts.size() && i < 8; ++i) list += (i ? ", " : "") + parts[i];
      if (parts.size() > 8) list += ", ...";
      throw std::runtime_error(path + ": holds " + std::to_string(parts.size()) + " top-level parts (" + list +
                               "); pick one with --part NAME, or --merge to fit them as one rigid body");
    }
    collect(c, top, nullptr);
  }
  return std::move(c.part);
}

}  // namespace

Part readPart(const std::string& path, const ReadOptions& options) {
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& ch : extension) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  // Coin's STL reader fails on the second different STL file in a process: STL is read here.
  Part part = extension == ".stl" ? readStl(path, options.scale) : readScene(path, options);
  if (part.triangles == 0 && part.primitives == 0)
    throw std::runtime_error(path + (options.part.empty() ? "" : " (part " + options.part + ")") +
                             ": no triangles or solid primitives (nothing to fit)");
  double max_abs = 0.0;
  for (const Vec3& p : part.points) max_abs = std::max(max_abs, p.cwiseAbs().maxCoeff());
  for (const Sphere& b : part.balls) max_abs = std::max(max_abs, b.center.cwiseAbs().maxCoeff() + b.radius);
  for (const Vec3& p : part.points)
    if (!p.allFinite()) throw std::runtime_error(path + ": non-finite vertex coordinates");
  // Coin and STL store single-precision coordinates (Coin its matrices too): cover their rounding.
  part.coordinate_guard = 1e-6 * max_abs;
  return part;
}

}  // namespace kccd::modelling
