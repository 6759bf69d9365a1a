#include "kccd/modelling/urdf_import.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <mutex>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>

#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "kccd/model.hpp"
#include "kccd/modelling/convex_hull.hpp"
#include "kccd/modelling/convex_pieces.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/part.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::modelling {
namespace {

std::string vec(double x, double y, double z) {
  std::string s = "[";
  s.append(yamlNumber(x)).append(", ").append(yamlNumber(y)).append(", ").append(yamlNumber(z)).append("]");
  return s;
}

Eigen::Affine3d toEigen(const urdf::Pose& p) {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.translation() = Vec3(p.position.x, p.position.y, p.position.z);
  t.linear() =
      Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  return t;
}

std::string resolveMesh(const std::string& urdf_path, const std::string& link, const std::string& uri,
                        const ImportOptions& options) {
  namespace fs = std::filesystem;
  const std::string where = urdf_path + ": link " + link + ": mesh " + uri;
  if (uri.rfind("package://", 0) == 0) {
    const std::string rest = uri.substr(10);
    const std::size_t slash = rest.find('/');
    const std::string package = rest.substr(0, slash);
    auto it = options.packages.find(package);
    if (it == options.packages.end())
      throw UrdfError(where + ": unknown package '" + package + "' (give --package-path " + package + "=DIR)");
    return (fs::path(it->second) / (slash == std::string::npos ? "" : rest.substr(slash + 1))).string();
  }
  if (uri.rfind("file://", 0) == 0) return uri.substr(7);
  const fs::path p(uri);
  return p.is_absolute() ? uri : (fs::path(urdf_path).parent_path() / p).string();
}

Part linkPart(const std::string& urdf_path, const urdf::Link& link, const ImportOptions& options) {
  Part part;
  for (const urdf::CollisionSharedPtr& c : link.collision_array) {
    if (!c || !c->geometry) continue;
    const Eigen::Affine3d t = toEigen(c->origin);
    switch (c->geometry->type) {
      case urdf::Geometry::SPHERE:
        part.addSphere(t, static_cast<const urdf::Sphere&>(*c->geometry).radius);
        break;
      case urdf::Geometry::BOX: {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(*c->geometry).dim;
        part.addBox(t, Vec3(d.x, d.y, d.z));
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& cyl = static_cast<const urdf::Cylinder&>(*c->geometry);
        // URDF cylinders lie along z; the cover is built along y.
        const Eigen::Affine3d along_z = t * Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitX());
        part.addCylinderY(along_z, cyl.radius, cyl.length);
        break;
      }
      case urdf::Geometry::MESH: {
        const auto& mesh = static_cast<const urdf::Mesh&>(*c->geometry);
        const std::string file = resolveMesh(urdf_path, link.name, mesh.filename, options);
        Part m;
        try {
          m = readPart(file, {.merge = true, .scale = Vec3(mesh.scale.x, mesh.scale.y, mesh.scale.z)});
        } catch (const InputError& e) {  // the mesh file's own error, placed in the URDF
          throw UrdfError(urdf_path + ": link " + link.name + ": " + e.what());
        }
        for (Vec3& p : m.points) p = t * p;
        for (Sphere& s : m.balls) s.center = t * s.center;  // rigid: radii unchanged
        part.append(m);
        break;
      }
    }
  }
  return part;
}

// The link's <visual> elements as `visuals:` entries in `frame` (mesh files resolved like the
// collision meshes, written as absolute paths; the material's colour when it has one).
void writeVisuals(std::ostringstream& out, const std::string& urdf_path, const urdf::Link& link,
                  const std::string& frame, const ImportOptions& options) {
  for (const urdf::VisualSharedPtr& v : link.visual_array) {
    if (!v || !v->geometry) continue;
    const urdf::Pose& o = v->origin;
    double r, p, y;
    o.rotation.getRPY(r, p, y);
    out << "  - frame: " << frame << "\n";
    switch (v->geometry->type) {
      case urdf::Geometry::SPHERE:
        out << "    sphere: " << yamlNumber(static_cast<const urdf::Sphere&>(*v->geometry).radius) << "\n";
        break;
      case urdf::Geometry::BOX: {
        const urdf::Vector3& d = static_cast<const urdf::Box&>(*v->geometry).dim;
        out << "    box: " << vec(d.x, d.y, d.z) << "\n";
        break;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& c = static_cast<const urdf::Cylinder&>(*v->geometry);
        out << "    cylinder: {radius: " << yamlNumber(c.radius) << ", length: " << yamlNumber(c.length) << "}\n";
        break;
      }
      case urdf::Geometry::MESH: {
        const auto& mesh = static_cast<const urdf::Mesh&>(*v->geometry);
        std::string file;
        try {
          file = resolveMesh(urdf_path, link.name, mesh.filename, options);
        } catch (const UrdfError& e) {
          throw UrdfError(std::string(e.what()) + " (a visual; or import with --no-visuals)");
        }
        std::error_code ec;
        if (!std::filesystem::is_regular_file(file, ec))
          throw UrdfError(urdf_path + ": link " + link.name + ": visual mesh " + printable(mesh.filename, 1024) + ": " +
                          printable(file, 1024) + " is not a file (or import with --no-visuals)");
        out << "    mesh: " << yamlQuoted(std::filesystem::absolute(file).lexically_normal().string()) << "\n";
        if (mesh.scale.x != 1 || mesh.scale.y != 1 || mesh.scale.z != 1)
          out << "    scale: " << vec(mesh.scale.x, mesh.scale.y, mesh.scale.z) << "\n";
        break;
      }
    }
    out << "    origin: {xyz: " << vec(o.position.x, o.position.y, o.position.z) << ", rpy: " << vec(r, p, y) << "}\n";
    // A material with a colour (urdfdom leaves a texture-only one black: not written).
    if (v->material && !(v->material->color.r == 0 && v->material->color.g == 0 && v->material->color.b == 0 &&
                         !v->material->texture_filename.empty())) {
      const urdf::Color& c = v->material->color;
      auto unit = [](float x) { return yamlNumber(std::clamp(static_cast<double>(x), 0.0, 1.0)); };
      out << "    colour: [" << unit(c.r) << ", " << unit(c.g) << ", " << unit(c.b) << ", " << unit(c.a) << "]\n";
    }
  }
}

void loadXml(tinyxml2::XMLDocument& doc, const std::string& text, const std::string& path) {
  if (doc.Parse(text.data(), text.size()) == tinyxml2::XML_SUCCESS) return;
  throw UrdfError(path + ":" + std::to_string(doc.ErrorLineNum()) + ": malformed XML (" +
                  tinyxml2::XMLDocument::ErrorIDToName(doc.ErrorID()) + ")");
}

// urdfdom reports through console_bridge, several lines on the console per problem: they are
// kept here instead, the first error for the one-line message.
class CaptureLog : public console_bridge::OutputHandler {
 public:
  std::string first;
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first.empty()) first = printable(text, 300);
  }
};

struct UrdfParse {
  urdf::ModelInterfaceSharedPtr model;
  std::string error;
};

UrdfParse parseWithUrdfdom(const std::string& text) {
  static std::mutex mutex;  // console_bridge's handler is process-wide
  std::lock_guard<std::mutex> lock(mutex);
  CaptureLog capture;
  const console_bridge::LogLevel level = console_bridge::getLogLevel();
  console_bridge::useOutputHandler(&capture);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  UrdfParse result;
  try {
    result.model = urdf::parseURDF(text);
  } catch (...) {
    console_bridge::restorePreviousOutputHandler();
    console_bridge::setLogLevel(level);
    throw;
  }
  console_bridge::restorePreviousOutputHandler();
  console_bridge::setLogLevel(level);
  result.error = capture.first;
  return result;
}

// Where a problem is: "file:line: link 'name': collision N: ".
struct Place {
  const std::string& path;
  std::string what;
  UrdfError error(const tinyxml2::XMLElement* e, const std::string& problem) const {
    return UrdfError(path + ":" + std::to_string(e->GetLineNum()) + ": " + what + problem);
  }
};

// The numbers of an attribute, as urdfdom reads them but refusing what it would bend: exactly
// `count` finite numbers. Missing: `fallback` (empty: required).
std::vector<double> numbers(const Place& at, const tinyxml2::XMLElement* e, const char* attribute, std::size_t count,
                            const std::vector<double>& fallback = {}) {
  const std::string name = std::string(e->Name()) + " " + attribute;
  const char* text = e->Attribute(attribute);
  if (!text) {
    if (fallback.empty()) throw at.error(e, name + ": missing");
    return fallback;
  }
  std::vector<double> out;
  const std::string s = text;
  std::size_t i = 0;
  while (true) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    if (i == s.size()) break;
    std::size_t j = i;
    while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
    const std::string word = s.substr(i, j - i);
    double v = 0;
    const char* begin = word.data() + (word[0] == '+' ? 1 : 0);
    const auto [end, ec] = std::from_chars(begin, word.data() + word.size(), v);
    if (ec == std::errc::result_out_of_range ||
        (ec == std::errc() && end == word.data() + word.size() && !std::isfinite(v)))
      throw at.error(e, name + ": '" + printable(word) + "' is not a finite number");
    if (ec != std::errc() || end != word.data() + word.size())
      throw at.error(e, name + ": '" + printable(word) + "' is not a number");
    out.push_back(v);
    i = j;
  }
  if (out.size() != count)
    throw at.error(e, name + ": " + std::to_string(out.size()) + " numbers, expected " + std::to_string(count));
  return out;
}

void checkOrigin(const Place& at, const tinyxml2::XMLElement* parent) {
  if (const tinyxml2::XMLElement* o = parent->FirstChildElement("origin")) {
    numbers(at, o, "xyz", 3, {0, 0, 0});
    numbers(at, o, "rpy", 3, {0, 0, 0});
  }
}

void nonNegative(const Place& at, const tinyxml2::XMLElement* e, const char* attribute, const std::vector<double>& v) {
  for (const double x : v)
    if (x < 0) throw at.error(e, std::string(e->Name()) + " " + attribute + ": " + yamlNumber(x) + " is negative");
}

// Every <collision> of every link checked as the fit reads it; returns the number per link.
std::map<std::string, int> checkCollisions(const tinyxml2::XMLDocument& doc, const std::string& path) {
  std::map<std::string, int> counts;
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) return counts;  // urdfdom names the problem
  for (const tinyxml2::XMLElement* link = robot->FirstChildElement("link"); link;
       link = link->NextSiblingElement("link")) {
    const char* name = link->Attribute("name");
    const std::string link_name = name ? name : "";
    int index = 0;
    for (const tinyxml2::XMLElement* c = link->FirstChildElement("collision"); c;
         c = c->NextSiblingElement("collision")) {
      const Place at{path, "link '" + printable(link_name) + "': collision " + std::to_string(++index) + ": "};
      checkOrigin(at, c);
      const tinyxml2::XMLElement* geometry = c->FirstChildElement("geometry");
      if (!geometry) throw at.error(c, "no <geometry>");
      const tinyxml2::XMLElement* shape = geometry->FirstChildElement();
      if (!shape) throw at.error(geometry, "<geometry> holds no shape");
      if (shape->NextSiblingElement())
        throw at.error(shape->NextSiblingElement(), "<geometry> holds more than one shape");
      const std::string type = shape->Name();
      if (type == "box") {
        nonNegative(at, shape, "size", numbers(at, shape, "size", 3));
      } else if (type == "sphere") {
        nonNegative(at, shape, "radius", numbers(at, shape, "radius", 1));
      } else if (type == "cylinder") {
        nonNegative(at, shape, "radius", numbers(at, shape, "radius", 1));
        nonNegative(at, shape, "length", numbers(at, shape, "length", 1));
      } else if (type == "mesh") {
        const char* file = shape->Attribute("filename");
        if (!file || !*file) throw at.error(shape, "mesh filename: missing");
        for (const double x : numbers(at, shape, "scale", 3, {1, 1, 1}))
          if (x == 0) throw at.error(shape, "mesh scale: a factor of 0 flattens the mesh");
      } else {
        throw at.error(shape, "<" + printable(type) + ">: not a URDF shape (box, cylinder, sphere, mesh)");
      }
    }
    counts[link_name] += index;
  }
  for (const tinyxml2::XMLElement* joint = robot->FirstChildElement("joint"); joint;
       joint = joint->NextSiblingElement("joint")) {
    const char* name = joint->Attribute("name");
    const Place at{path, "joint '" + printable(name ? name : "") + "': "};
    checkOrigin(at, joint);
    if (const tinyxml2::XMLElement* axis = joint->FirstChildElement("axis")) {
      const std::vector<double> a = numbers(at, axis, "xyz", 3, {1, 0, 0});
      const char* type = joint->Attribute("type");
      const bool moves = type && std::string(type) != "fixed";
      if (moves && a[0] == 0.0 && a[1] == 0.0 && a[2] == 0.0) throw at.error(axis, "axis xyz: zero axis");
    }
    if (const tinyxml2::XMLElement* limit = joint->FirstChildElement("limit")) {
      numbers(at, limit, "lower", 1, {0});
      numbers(at, limit, "upper", 1, {0});
    }
  }
  return counts;
}

// The line of the first <collision> of link `name` (for messages about what urdfdom kept).
int collisionLine(const tinyxml2::XMLDocument& doc, const std::string& name) {
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  for (const tinyxml2::XMLElement* link = robot ? robot->FirstChildElement("link") : nullptr; link;
       link = link->NextSiblingElement("link"))
    if (const char* n = link->Attribute("name"); n && name == n) {
      const tinyxml2::XMLElement* c = link->FirstChildElement("collision");
      return (c ? c : link)->GetLineNum();
    }
  return 0;
}

std::vector<IgnoreEntry> readSrdf(const tinyxml2::XMLDocument& doc, const std::string& path,
                                  const std::set<std::string>& links,
                                  const std::map<std::string, std::vector<std::string>>& bodies) {
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw UrdfError(path + ": not an SRDF file (no <robot> element)");
  std::vector<IgnoreEntry> out;
  for (const tinyxml2::XMLElement* e = robot->FirstChildElement("disable_collisions"); e;
       e = e->NextSiblingElement("disable_collisions")) {
    const char* a = e->Attribute("link1");
    const char* b = e->Attribute("link2");
    if (!a || !b)
      throw UrdfError(path + ":" + std::to_string(e->GetLineNum()) + ": disable_collisions needs link1 and link2");
    for (const char* l : {a, b})
      if (!links.count(l))
        throw UrdfError(path + ":" + std::to_string(e->GetLineNum()) + ": link '" + l + "' is not in the URDF");
    if (bodies.count(a) && bodies.count(b) && std::string(a) != b)
      for (const std::string& pa : bodies.at(a))  // every piece of one link against every piece of the other
        for (const std::string& pb : bodies.at(b)) out.push_back({pa, pb, IgnoreReason::Srdf});
  }
  return out;
}

// Each link's collision geometry fitted as requested: the bodies' entries, each link's bodies
// (the SRDF's pairs name links) and the largest body's point count.
struct FittedLinks {
  std::string yaml;
  std::map<std::string, std::vector<std::string>> pieces_of;  // link -> its bodies
  std::size_t most_points = 0;
};

FittedLinks fitLinks(const std::string& path, const std::vector<urdf::LinkConstSharedPtr>& order,
                     const std::map<std::string, std::string>& frame_of, const ImportOptions& options) {
  FittedLinks out;
  std::string bodies;
  int done = 0, with_geometry = 0;
  for (const auto& link : order)
    if (!link->collision_array.empty()) ++with_geometry;
  for (const auto& link : order) {
    if (link->collision_array.empty()) continue;
    const Part part = linkPart(path, *link, options);
    if (part.empty()) continue;
    const FittedPart f = fitPart(part, options.fit, [&](double d) {
      if (options.progress) options.progress((done + d) / std::max(1, with_geometry));
    });
    const int count = static_cast<int>(f.pieces.size());
    for (int k = 0; k < count; ++k) {
      const FitResult& r = f.pieces[static_cast<std::size_t>(k)].fit;
      const std::string name = pieceName(link->name, k, count);
      const std::string how = options.fit.method == FitMethod::Hull ? "the convex hull of the collision geometry"
                              : options.fit.method == FitMethod::Tolerance
                                  ? std::string(r.method) + ", " + std::to_string(r.points.size()) + " points"
                                  : "K = " + std::to_string(r.points.size()) + " fit";
      bodies += bodyYaml(
          {.name = name,
           .link = count > 1 ? link->name : std::string(),
           .frame = frame_of.at(link->name),
           .fit = &r,
           .link_comment = "piece " + std::to_string(k + 1) + " of " + std::to_string(count) + ", concavity about " +
                           yamlNumber(std::round(f.pieces[static_cast<std::size_t>(k)].concavity * 1e4) / 1e4) +
                           " m (the link's: " + yamlNumber(std::round(f.whole_concavity * 1e4) / 1e4) + " m)",
           .radius_comment =
               how + ": volume " + yamlNumber(r.volume) + " m^3, hull " + yamlNumber(r.hull_volume) + " m^3",
           .tolerance_comment = "at most this far outside the link's convex hull (m)"},
          "  ");
      out.pieces_of[link->name].push_back(name);
      out.most_points = std::max(out.most_points, r.points.size());
    }
    ++done;
  }
  out.yaml = std::move(bodies);
  return out;
}

}  // namespace

std::string importUrdf(const std::string& path, const ImportOptions& options) {
  // One read of the file: the XML checks and urdfdom see the same text. tinyxml2 bounds the
  // element nesting before urdfdom's parser (which recurses without a bound) sees it.
  const std::string urdf_text = readInputFile(path);
  tinyxml2::XMLDocument doc;  // for XML errors with line numbers
  loadXml(doc, urdf_text, path);
  const std::map<std::string, int> collisions = checkCollisions(doc, path);
  tinyxml2::XMLDocument srdf;  // checked before the (slow) fitting starts
  if (!options.srdf.empty()) loadXml(srdf, readInputFile(options.srdf), options.srdf);
  const UrdfParse parsed = parseWithUrdfdom(urdf_text);
  const urdf::ModelInterfaceSharedPtr& urdf = parsed.model;
  if (!urdf || !urdf->getRoot())
    throw UrdfError(path + ": not a valid URDF (" +
                    (parsed.error.empty() ? std::string("urdfdom rejected it") : "urdfdom: " + parsed.error) + ")");
  // urdfdom drops every collision of a link when one of them does not parse: whatever slipped
  // through the checks above must not become a link without geometry.
  for (const auto& [name, count] : collisions) {
    const urdf::LinkConstSharedPtr link = urdf->getLink(name);
    const std::size_t kept = link ? link->collision_array.size() : 0;
    if (kept != static_cast<std::size_t>(count))
      throw UrdfError(path + ":" + std::to_string(collisionLine(doc, name)) + ": link '" + printable(name) +
                      "': " + std::to_string(count) + " <collision> elements but urdfdom read " + std::to_string(kept) +
                      (parsed.error.empty() ? "" : " (" + parsed.error + ")"));
  }

  std::ostringstream joints, bodies;
  std::set<std::string> link_names;
  std::set<std::string> urdf_joint_names, joint_names;  // the URDF's; the model's
  for (const auto& [name, joint] : urdf->joints_) urdf_joint_names.insert(name);
  std::map<std::string, std::string> frame_of;  // link -> KCCD frame name
  std::deque<urdf::LinkConstSharedPtr> queue{urdf->getRoot()};
  frame_of[urdf->getRoot()->name] = "world";
  std::vector<urdf::LinkConstSharedPtr> order;
  while (!queue.empty()) {
    urdf::LinkConstSharedPtr link = queue.front();
    queue.pop_front();
    order.push_back(link);
    link_names.insert(link->name);
    for (const urdf::JointSharedPtr& j : link->child_joints) {
      const urdf::Pose& o = j->parent_to_joint_origin_transform;
      double r, p, y;
      o.rotation.getRPY(r, p, y);
      const std::string origin =
          "{xyz: " + vec(o.position.x, o.position.y, o.position.z) + ", rpy: " + vec(r, p, y) + "}";
      // One KCCD joint, or a chain of them, in the URDF joint's place; the child link hangs
      // from the last.
      std::string parent = frame_of.at(link->name);
      auto emit = [&](const std::string& name, const char* kind, const std::string& joint_origin, const Vec3* axis,
                      const std::string& note) {
        if ((name != j->name && urdf_joint_names.count(name) != 0) || !joint_names.insert(name).second)
          throw UrdfError(path + ": joint " + j->name + ": its KCCD joint " + name + " would repeat a joint name");
        joints << "  - name: " << name << "\n"
               << "    parent: " << parent << "\n"
               << "    type: " << kind << "\n"
               << "    origin: " << joint_origin << "\n";
        if (axis != nullptr) joints << "    axis: " << vec(axis->x(), axis->y(), axis->z()) << "\n";
        if (!note.empty()) joints << "    # " << note << "\n";
        parent = name;
      };
      const std::string zero = "{xyz: [0, 0, 0], rpy: [0, 0, 0]}";
      const Vec3 axis(j->axis.x, j->axis.y, j->axis.z);
      switch (j->type) {
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::CONTINUOUS:
        case urdf::Joint::PRISMATIC: {
          emit(j->name, j->type == urdf::Joint::PRISMATIC ? "prismatic" : "revolute", origin, &axis, "");
          if (j->type != urdf::Joint::CONTINUOUS && j->limits)
            joints << "    limits: [" << yamlNumber(j->limits->lower) << ", " << yamlNumber(j->limits->upper) << "]\n";
          break;
        }
        case urdf::Joint::FIXED:
          emit(j->name, "fixed", origin, nullptr, "");
          break;
        case urdf::Joint::FLOATING:
          // A measured 6-DOF pose: position, then orientation as a rotation vector.
          emit(j->name, "translation3d", origin, nullptr, "URDF floating joint " + j->name + ": position (x, y, z)");
          emit(j->name + "_rotation", "rotation3d", zero, nullptr,
               "URDF floating joint " + j->name + ": orientation (rotation vector)");
          break;
        case urdf::Joint::PLANAR: {
          // Motion in the plane through the joint frame's origin normal to the axis: two
          // prismatic joints along the plane's axes, then a revolute joint about the normal (the
          // swept volume of an interval box is exactly these three sweeps in turn).
          const double length = axis.norm();
          if (!(length > 0.0) || !std::isfinite(length))
            throw UrdfError(path + ": joint " + j->name + ": planar joint with a zero or non-finite axis");
          const Vec3 n = axis / length;
          const Vec3 pick = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
          const Vec3 u = (pick - pick.dot(n) * n).normalized(), v = n.cross(u);
          const std::string what = "URDF planar joint " + j->name;
          emit(j->name + "_x", "prismatic", origin, &u, what + ": first axis in the plane");
          emit(j->name + "_y", "prismatic", zero, &v, what + ": second axis in the plane");
          emit(j->name + "_yaw", "revolute", zero, &n, what + ": rotation about the plane's normal");
          break;
        }
        default:
          throw UrdfError(path + ": joint " + j->name + " has an unknown type");
      }
      if (j->mimic) joints << "    # mimics " << j->mimic->joint_name << " in the URDF: checked as independent\n";
      frame_of[j->child_link_name] = parent;
      const urdf::LinkConstSharedPtr child = urdf->getLink(j->child_link_name);
      if (child) queue.push_back(child);
    }
  }
  const FittedLinks fitted = fitLinks(path, order, frame_of, options);
  const std::map<std::string, std::vector<std::string>>& pieces_of = fitted.pieces_of;
  const std::size_t most_points = fitted.most_points;
  bodies << fitted.yaml;
  std::ostringstream visuals;
  if (options.visuals)
    for (const auto& link : order) writeVisuals(visuals, path, *link, frame_of.at(link->name), options);
  std::vector<IgnoreEntry> ignore;
  if (!options.srdf.empty()) ignore = readSrdf(srdf, options.srdf, link_names, pieces_of);

  const auto compose = [&] {
    std::ostringstream out;
    out << "# Imported from " << std::filesystem::path(path).filename().string()
        << (options.srdf.empty() ? "" : " and " + std::filesystem::path(options.srdf).filename().string())
        << " by kccd import ("
        << (options.fit.method == FitMethod::Hull ? std::string("convex hulls, no fit")
            : options.fit.method == FitMethod::Tolerance
                ? "each link within " + yamlNumber(options.fit.tolerance * 1e3) + " mm of its hull"
                : std::to_string(options.fit.points) + " core points per link")
        << (options.fit.max_pieces > 1
                ? ", concave links in up to " + std::to_string(options.fit.max_pieces) + " pieces (concavity above " +
                      yamlNumber(options.fit.concavity * 1e3) + " mm)"
                : std::string())
        << ")\n"
        << "kccd: 1\n"
        << "name: " << urdf->getName() << "\n"
        << "safety_margin: " << yamlNumber(options.safety_margin) << "\n";
    // A point budget below a body's point count makes the checker reduce that body on every query
    // (a larger radius, and the reduction's own cost): the budget holds the largest body.
    if (most_points > 32)
      out << "point_budget: " << std::min<std::size_t>(most_points, 4096)
          << "   # the largest body's core points: no body is reduced in a static query\n";
    const std::string jt = joints.str(), bt = bodies.str();
    out << "joints:" << (jt.empty() ? " []\n" : "\n" + jt);
    out << "bodies:" << (bt.empty() ? " []\n" : "\n" + bt);
    out << "pairs:   # ignore [a, b, why]: rigid, adjacent (kccd pairs --help), srdf, never, always_touching\n"
           "  check: all\n  ignore: "
        << flowPairs(ignore, 11) << "\n";
    if (const std::string vt = visuals.str(); !vt.empty()) out << "visuals:   # appearance only, never checked\n" << vt;
    return out.str();
  };
  const auto load = [&](const std::string& text) {
    try {
      return parseModel(text, path + " (imported)");
    } catch (const ModelError& e) {
      throw UrdfError(path + ": the imported model does not load: " + e.what());
    }
  };
  // Rigidly attached and adjacent links (MoveIt's rule), then the SRDF's pairs.
  ignore = structuralIgnores(load(compose()), {.keep_adjacent = options.keep_adjacent, .world_is_link = true}).ignore;
  const std::string text = compose();
  (void)load(text);
  if (options.progress) options.progress(1.0);
  return text;
}

}  // namespace kccd::modelling
