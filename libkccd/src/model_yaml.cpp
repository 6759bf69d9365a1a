// The `kccd: 1` YAML model format (docs/formats.md section 2). Every error names the file, the
// line and column, and the field; loading stops at the first one.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "kccd/file_reader.hpp"
#include "kccd/model.hpp"
#include "kccd/rotation.hpp"
#include "kccd/yaml_reader.hpp"

namespace kccd {
namespace {

// The model's own checks of a node, on top of the YAML reader's.
class Reader : public YamlReader {
 public:
  using YamlReader::YamlReader;

  // A length in metres: finite and within kMaxModelLength.
  double length(const YAML::Node& n, const std::string& field) const {
    const double v = number(n, field);
    if (std::abs(v) > kMaxModelLength) fail(n, field, "beyond the largest length a model may give (1e6 m)");
    return v;
  }

  Vec3 point(const YAML::Node& n, const std::string& field) const {
    const Vec3 v = vec<3>(n, field);
    for (int k = 0; k < 3; ++k)
      if (std::abs(v[k]) > kMaxModelLength)
        fail(n[k], field + "[" + std::to_string(k) + "]", "beyond the largest length a model may give (1e6 m)");
    return v;
  }
};

Pose parseOrigin(const Reader& r, const YAML::Node& n, const std::string& field) {
  r.onlyKeys(n, field, {"xyz", "rpy"});
  Pose pose = Pose::Identity();
  if (n["xyz"]) pose.translation() = r.point(n["xyz"], field + ".xyz");
  if (n["rpy"]) {
    const Vec3 rpy = r.vec<3>(n["rpy"], field + ".rpy");
    pose.linear() = rotationFromRpy(rpy);
  }
  return pose;
}

JointType parseType(const Reader& r, const YAML::Node& n, const std::string& field) {
  const std::string t = r.text(n, field);
  if (t == "fixed") return JointType::Fixed;
  if (t == "revolute") return JointType::Revolute;
  if (t == "prismatic") return JointType::Prismatic;
  if (t == "translation3d") return JointType::Translation3d;
  if (t == "rotation3d") return JointType::Rotation3d;
  r.fail(n, field, "unknown joint type '" + t + "' (fixed, revolute, prismatic, translation3d, rotation3d)");
}

SweepMode parseSweep(const Reader& r, const YAML::Node& n, const std::string& field) {
  const std::string t = r.text(n, field);
  if (t == "exact") return SweepMode::Exact;
  // The retired chords-only mode: its verdicts cost about as much as accurate's at many times the
  // false alarms. Accurate is never looser, so a file that asks for it gets accurate.
  if (t == "accurate" || t == "fast") return SweepMode::Accurate;
  r.fail(n, field, "unknown sweep mode '" + t + "' (exact, accurate)");
}

// The required `frame` of the entry `n` named `field` in messages: kWorld for "world", else a
// joint defined earlier.
int parseFrame(const Reader& r, const YAML::Node& n, const std::string& field, const Model& m) {
  const std::string frame = r.text(r.require(n, "frame", field), field + ".frame");
  if (frame == "world") return kWorld;
  const int joint = m.jointIndex(frame);
  if (joint < 0) r.fail(n["frame"], field + ".frame", "unknown joint '" + frame + "'");
  return joint;
}

void parseJoints(const Reader& r, const YAML::Node& list, Model& m) {
  if (!list.IsSequence()) r.fail(list, "joints", "expected a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string f = "joints[" + std::to_string(i) + "]";
    r.onlyKeys(n, f, {"name", "parent", "type", "origin", "axis", "sweep", "limits", "error"});
    Joint j;
    j.name = r.text(r.require(n, "name", f), f + ".name");
    const std::string fn = "joint '" + j.name + "'";
    if (j.name == "world") r.fail(n["name"], f + ".name", "'world' is reserved");
    if (m.jointIndex(j.name) >= 0) r.fail(n["name"], f + ".name", "duplicate joint name '" + j.name + "'");
    const std::string parent = r.text(r.require(n, "parent", fn), fn + ".parent");
    if (parent != "world") {
      j.parent = m.jointIndex(parent);
      if (j.parent < 0) r.fail(n["parent"], fn + ".parent", "'" + parent + "' is not a joint defined earlier");
    }
    j.type = parseType(r, r.require(n, "type", fn), fn + ".type");
    if (n["origin"]) j.origin = parseOrigin(r, n["origin"], fn + ".origin");
    const bool one_dof = j.type == JointType::Revolute || j.type == JointType::Prismatic;
    if (one_dof) {
      const YAML::Node axis = r.require(n, "axis", fn);
      const Vec3 a = r.vec<3>(axis, fn + ".axis");
      // Scaled by its largest component first, so tiny and huge components normalise alike.
      const double scale = a.cwiseAbs().maxCoeff();
      if (!(scale > 0.0)) r.fail(axis, fn + ".axis", "zero axis");
      j.axis = (a / scale).normalized();
    } else if (n["axis"]) {
      r.fail(n["axis"], fn + ".axis", std::string("a ") + toString(j.type) + " joint has no axis");
    }
    if (n["sweep"]) {
      j.sweep = parseSweep(r, n["sweep"], fn + ".sweep");
      if (j.type == JointType::Fixed) r.fail(n["sweep"], fn + ".sweep", "a fixed joint has no sweep mode");
    }
    if (n["limits"]) {
      const YAML::Node l = n["limits"];
      if (!one_dof) r.fail(l, fn + ".limits", "limits apply to revolute and prismatic joints only");
      if (!l.IsSequence() || l.size() != 2) r.fail(l, fn + ".limits", "expected [lower, upper]");
      const double lo = r.number(l[0], fn + ".limits[0]"), hi = r.number(l[1], fn + ".limits[1]");
      if (lo > hi) r.fail(l, fn + ".limits", "lower limit is above the upper limit");
      j.limits = std::array<double, 2>{lo, hi};
    }
    if (n["error"]) {
      if (j.type != JointType::Translation3d && j.type != JointType::Rotation3d)
        r.fail(n["error"], fn + ".error", "an error bound applies to translation3d and rotation3d joints only");
      j.error = j.type == JointType::Translation3d ? r.length(n["error"], fn + ".error")
                                                   : r.number(n["error"], fn + ".error");
      if (j.error < 0.0) r.fail(n["error"], fn + ".error", "must be >= 0");
    }
    m.joints.push_back(std::move(j));
  }
}

void parseBodies(const Reader& r, const YAML::Node& list, Model& m) {
  if (!list.IsSequence()) r.fail(list, "bodies", "expected a list");
  if (list.size() > kMaxModelBodies)
    r.fail(
        list, "bodies",
        std::to_string(list.size()) + " bodies, more than a model may hold (" + std::to_string(kMaxModelBodies) + ")");
  std::map<std::string, int> links;  // link name -> its first piece (body index)
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string f = "bodies[" + std::to_string(i) + "]";
    r.onlyKeys(n, f, {"name", "frame", "points", "radius", "link", "tolerance"});
    Body b;
    b.name = r.text(r.require(n, "name", f), f + ".name");
    const std::string fb = "body '" + b.name + "'";
    if (m.bodyIndex(b.name) >= 0) r.fail(n["name"], f + ".name", "duplicate body name '" + b.name + "'");
    b.frame = parseFrame(r, n, fb, m);
    const YAML::Node pts = r.require(n, "points", fb);
    if (!pts.IsSequence()) r.fail(pts, fb + ".points", "expected a list of [x, y, z]");
    if (pts.size() == 0) r.fail(pts, fb + ".points", "empty point list");
    for (std::size_t k = 0; k < pts.size(); ++k)
      b.points.push_back(r.point(pts[k], fb + ".points[" + std::to_string(k) + "]"));
    const YAML::Node rad = r.require(n, "radius", fb);
    b.radius = r.length(rad, fb + ".radius");
    if (b.radius < 0.0) r.fail(rad, fb + ".radius", "negative radius");
    if (n["tolerance"]) {
      b.tolerance = r.length(n["tolerance"], fb + ".tolerance");
      if (b.tolerance < 0.0) r.fail(n["tolerance"], fb + ".tolerance", "must be >= 0");
    }
    if (n["link"]) {
      b.link = r.text(n["link"], fb + ".link");
      if (b.link.empty()) r.fail(n["link"], fb + ".link", "empty link name");
      // Pieces of one link move together: the same frame as the link's other pieces, and no
      // whole body may carry the link's name.
      const int whole = m.bodyIndex(b.link);
      if (whole >= 0 && m.bodies[whole].link.empty())
        r.fail(n["link"], fb + ".link", "link '" + b.link + "' is also a whole body's name");
      const auto [it, fresh] = links.try_emplace(b.link, static_cast<int>(m.bodies.size()));
      const Body& first = fresh ? b : m.bodies[it->second];
      if (first.frame != b.frame)
        r.fail(n["link"], fb + ".link",
               "piece of link '" + b.link + "' in frame '" + m.frameName(b.frame) + "', but body '" + first.name +
                   "' of that link is in frame '" + m.frameName(first.frame) + "'");
    } else if (const auto it = links.find(b.name); it != links.end()) {
      r.fail(n["name"], f + ".name",
             "'" + b.name + "' is already the link of body '" + m.bodies[it->second].name + "'");
    }
    m.bodies.push_back(std::move(b));
  }
}

void parseVisuals(const Reader& r, const YAML::Node& list, Model& m, const std::string& source) {
  if (!list.IsSequence()) r.fail(list, "visuals", "expected a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node n = list[i];
    const std::string f = "visuals[" + std::to_string(i) + "]";
    r.onlyKeys(n, f, {"frame", "mesh", "scale", "box", "cylinder", "sphere", "origin", "colour"});
    Visual v;
    v.frame = parseFrame(r, n, f, m);
    int shapes = 0;
    for (const char* key : {"mesh", "box", "cylinder", "sphere"}) shapes += n[key] ? 1 : 0;
    if (shapes != 1) r.fail(n, f, "exactly one of mesh, box, cylinder, sphere");
    auto positive = [&](const YAML::Node& node, const std::string& field) {
      const double x = r.length(node, field);
      if (!(x > 0.0)) r.fail(node, field, "must be > 0");
      return x;
    };
    if (n["mesh"]) {
      v.shape = Visual::Shape::Mesh;
      std::string mesh = r.text(n["mesh"], f + ".mesh");
      if (mesh.rfind("package://", 0) == 0)
        r.fail(n["mesh"], f + ".mesh",
               "package:// paths are resolved by kccd import (--package-path); give a file path");
      if (mesh.rfind("file://", 0) == 0) mesh.erase(0, 7);
      const std::filesystem::path file = mesh;
      // Relative to the model file's folder when the model came from a file.
      const std::filesystem::path folder = std::filesystem::path(source).parent_path();
      v.mesh = (file.is_relative() ? folder / file : file).lexically_normal().string();
      if (n["scale"]) {
        v.scale = r.vec<3>(n["scale"], f + ".scale");
        for (int k = 0; k < 3; ++k)
          if (v.scale[k] == 0.0 || std::abs(v.scale[k]) > kMaxModelLength)
            r.fail(n["scale"], f + ".scale", "factors must be non-zero and at most 1e6");
      }
    } else if (n["scale"]) {
      r.fail(n["scale"], f + ".scale", "a scale applies to meshes only");
    }
    if (n["box"]) {
      v.shape = Visual::Shape::Box;
      const YAML::Node b = n["box"];
      if (!b.IsSequence() || b.size() != 3) r.fail(b, f + ".box", "expected [x, y, z] sizes");
      for (int k = 0; k < 3; ++k) v.size[k] = positive(b[k], f + ".box[" + std::to_string(k) + "]");
    }
    if (n["cylinder"]) {
      v.shape = Visual::Shape::Cylinder;
      const YAML::Node c = n["cylinder"];
      r.onlyKeys(c, f + ".cylinder", {"radius", "length"});
      const double radius = positive(r.require(c, "radius", f + ".cylinder"), f + ".cylinder.radius");
      v.size = Vec3(radius, radius, positive(r.require(c, "length", f + ".cylinder"), f + ".cylinder.length"));
    }
    if (n["sphere"]) {
      v.shape = Visual::Shape::Sphere;
      const double radius = positive(n["sphere"], f + ".sphere");
      v.size = Vec3(radius, radius, radius);
    }
    if (n["origin"]) v.origin = parseOrigin(r, n["origin"], f + ".origin");
    if (n["colour"]) {
      const YAML::Node c = n["colour"];
      if (!c.IsSequence() || (c.size() != 3 && c.size() != 4))
        r.fail(c, f + ".colour", "expected [r, g, b] or [r, g, b, a] in 0..1");
      for (std::size_t k = 0; k < c.size(); ++k) {
        const double x = r.number(c[k], f + ".colour[" + std::to_string(k) + "]");
        if (x < 0.0 || x > 1.0) r.fail(c[k], f + ".colour[" + std::to_string(k) + "]", "must be in 0..1");
        v.colour[k] = x;
      }
    }
    m.visuals.push_back(std::move(v));
  }
}

// A list of [body, body] entries; with `reasons`, an entry may carry a third element, the
// IgnoreReason word (stored in `reasons_out`).
std::vector<std::array<int, 2>> parsePairList(const Reader& r, const YAML::Node& list, const Model& m,
                                              const std::string& field,
                                              std::vector<IgnoredPair>* reasons_out = nullptr) {
  std::vector<std::array<int, 2>> out;
  const char* shape = reasons_out ? "[body, body] or [body, body, reason]" : "[body, body]";
  if (!list.IsSequence()) r.fail(list, field, std::string("expected a list of ") + shape);
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node p = list[i];
    const std::string f = field + "[" + std::to_string(i) + "]";
    if (!p.IsSequence() || p.size() < 2 || p.size() > (reasons_out ? 3u : 2u))
      r.fail(p, f, std::string("expected ") + shape);
    std::array<int, 2> ids{};
    for (int k = 0; k < 2; ++k) {
      const std::string name = r.text(p[k], f);
      ids[k] = m.bodyIndex(name);
      if (ids[k] < 0) r.fail(p[k], f, "unknown body '" + name + "'");
    }
    if (ids[0] == ids[1]) r.fail(p, f, "a body paired with itself");
    if (reasons_out) {
      IgnoredPair entry{ids[0], ids[1], IgnoreReason::User};
      if (p.size() == 3) {
        const std::string word = r.text(p[2], f + ".reason");
        if (!parseIgnoreReason(word, entry.reason))
          r.fail(
              p[2], f + ".reason",
              "unknown reason '" + printable(word, 40) + "' (user, adjacent, rigid, never, always_touching or srdf)");
      }
      reasons_out->push_back(entry);
    }
    out.push_back(ids);
  }
  return out;
}

// The model in `yaml_text`; every failure an InputError (parseModel makes it a ModelError).
Model parse(const std::string& yaml_text, const std::string& source) {
  const Reader r(source);
  const YAML::Node root = r.load(yaml_text);  // one document, unique keys, bounded nesting
  if (!root.IsMap()) r.fail(root, "model", "expected a mapping with kccd, joints, bodies");
  r.onlyKeys(root, "model", {"kccd", "name", "safety_margin", "point_budget", "joints", "bodies", "pairs", "visuals"});
  const YAML::Node version = r.require(root, "kccd", "model");
  if (!version.IsScalar() || version.Scalar() != "1")
    r.fail(version, "kccd", "unsupported format version '" + printable(version.Scalar()) + "' (this build reads 1)");
  Model m;
  m.name = root["name"] ? r.text(root["name"], "name") : std::string("model");
  if (root["safety_margin"]) {
    m.safety_margin = r.length(root["safety_margin"], "safety_margin");
    if (m.safety_margin < 0.0) r.fail(root["safety_margin"], "safety_margin", "must be >= 0");
  }
  if (root["point_budget"]) {
    const double b = r.number(root["point_budget"], "point_budget");
    if (b != std::floor(b) || b < 4 || b > 4096)
      r.fail(root["point_budget"], "point_budget", "must be an integer in 4..4096");
    m.point_budget = static_cast<int>(b);
  }
  if (root["joints"]) parseJoints(r, root["joints"], m);
  parseBodies(r, r.require(root, "bodies", "model"), m);
  if (m.bodies.empty()) r.fail(root["bodies"], "bodies", "a model needs at least one body");
  if (root["visuals"]) parseVisuals(r, root["visuals"], m, source);
  bool check_all = true;
  std::vector<std::array<int, 2>> ignore, include;
  if (const YAML::Node pairs = root["pairs"]) {
    r.onlyKeys(pairs, "pairs", {"check", "ignore", "include"});
    if (pairs["check"]) {
      const std::string c = r.text(pairs["check"], "pairs.check");
      if (c != "all" && c != "none") r.fail(pairs["check"], "pairs.check", "expected 'all' or 'none', got '" + c + "'");
      check_all = c == "all";
    }
    if (pairs["ignore"]) ignore = parsePairList(r, pairs["ignore"], m, "pairs.ignore", &m.ignored);
    if (pairs["include"]) include = parsePairList(r, pairs["include"], m, "pairs.include");
  }
  try {
    m.finalize(check_all, ignore, include);
  } catch (const ModelError& e) {
    r.fail(root["pairs"], "pairs", e.what());
  }
  return m;
}

}  // namespace

Model parseModel(const std::string& yaml_text, const std::string& source) {
  try {
    return parse(yaml_text, source);
  } catch (const ModelError&) {
    throw;
  } catch (const InputError& e) {
    throw ModelError(e.location(), e.problem());
  }
}

std::string readModelText(const std::string& path) {
  constexpr std::size_t kMaxBytes = YamlLimits{}.max_bytes;
  try {
    return readRegularFile(path, kMaxBytes, "model file");
  } catch (const FileError& e) {
    throw ModelError(e.location(), e.problem());
  }
}

Model loadModel(const std::string& path) { return parseModel(readModelText(path), path); }

}  // namespace kccd
