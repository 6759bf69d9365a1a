#include "kccd/modelling/urdf_import.hpp"

#include <cstdio>
#include <deque>
#include <filesystem>
#include <set>
#include <sstream>
#include <numbers>
#include <stdexcept>

#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include "kccd/model.hpp"
#include "kccd/modelling/fit.hpp"
#include "kccd/modelling/part.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::modelling {
namespace {

std::string num(double v) { return yamlNumber(v); }

std::string vec(double x, double y, double z) {
  std::string s = "[";
  s.append(num(x)).append(", ").append(num(y)).append(", ").append(num(z)).append("]");
  return s;
}

Eigen::Affine3d toEigen(const urdf::Pose& p) {
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  t.translation() = Vec3(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
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
      throw std::runtime_error(where + ": unknown package '" + package + "' (give --package-path " + package +
                               "=DIR)");
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
        } catch (const std::runtime_error& e) {
          throw std::runtime_error(urdf_path + ": link " + link.name + ": " + e.what());
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

void loadXml(tinyxml2::XMLDocument& doc, const std::string& path) {
  if (doc.LoadFile(path.c_str()) == tinyxml2::XML_SUCCESS) return;
  if (doc.ErrorID() == tinyxml2::XML_ERROR_FILE_NOT_FOUND || doc.ErrorID() == tinyxml2::XML_ERROR_FILE_COULD_NOT_BE_OPENED)
    throw std::runtime_error(path + ": cannot open the file");
  throw std::runtime_error(path + ":" + std::to_string(doc.ErrorLineNum()) + ": malformed XML (" +
                           tinyxml2::XMLDocument::ErrorIDToName(doc.ErrorID()) + ")");
}

std::vector<std::array<std::string, 2>> readSrdf(const tinyxml2::XMLDocument& doc, const std::string& path,
                                                 const std::set<std::string>& links,
                                                 const std::set<std::string>& bodies) {
  const tinyxml2::XMLElement* robot = doc.FirstChildElement("robot");
  if (!robot) throw std::runtime_error(path + ": not an SRDF file (no <robot> element)");
  std::vector<std::array<std::string, 2>> out;
  for (const tinyxml2::XMLElement* e = robot->FirstChildElement("disable_collisions"); e;
       e = e->NextSiblingElement("disable_collisions")) {
    const char* a = e->Attribute("link1");
    const char* b = e->Attribute("link2");
    if (!a || !b)
      throw std::runtime_error(path + ":" + std::to_string(e->GetLineNum()) +
                               ": disable_collisions needs link1 and link2");
    for (const char* l : {a, b})
      if (!links.count(l))
        throw std::runtime_error(path + ":" + std::to_string(e->GetLineNum()) + ": link '" + l +
                                 "' is not in the URDF");
    if (bodies.count(a) && bodies.count(b) && std::string(a) != b) out.push_back({a, b});
  }
  return out;
}

}  // namespace

std::string importUrdf(const std::string& path, const ImportOptions& options) {
  tinyxml2::XMLDocument doc;  // for XML errors with line numbers
  loadXml(doc, path);
  tinyxml2::XMLDocument srdf;  // checked before the (slow) fitting starts
  if (!options.srdf.empty()) loadXml(srdf, options.srdf);
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDFFile(path);
  if (!urdf || !urdf->getRoot()) throw std::runtime_error(path + ": not a valid URDF (urdfdom rejected it)");

  std::ostringstream joints, bodies;
  std::set<std::string> link_names, body_names;
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
      const char* kind = nullptr;
      switch (j->type) {
        case urdf::Joint::REVOLUTE:
        case urdf::Joint::CONTINUOUS: kind = "revolute"; break;
        case urdf::Joint::PRISMATIC: kind = "prismatic"; break;
        case urdf::Joint::FIXED: kind = "fixed"; break;
        case urdf::Joint::FLOATING:
          throw std::runtime_error(path + ": joint " + j->name +
                                   " is floating: not supported (fixed, revolute, continuous, prismatic)");
        case urdf::Joint::PLANAR:
          throw std::runtime_error(path + ": joint " + j->name +
                                   " is planar: not supported (fixed, revolute, continuous, prismatic)");
        default: throw std::runtime_error(path + ": joint " + j->name + " has an unknown type");
      }
      const urdf::Pose& o = j->parent_to_joint_origin_transform;
      double r, p, y;
      o.rotation.getRPY(r, p, y);
      joints << "  - name: " << j->name << "\n"
             << "    parent: " << frame_of.at(link->name) << "\n"
             << "    type: " << kind << "\n"
             << "    origin: {xyz: " << vec(o.position.x, o.position.y, o.position.z) << ", rpy: " << vec(r, p, y)
             << "}\n";
      if (j->type != urdf::Joint::FIXED) {
        joints << "    axis: " << vec(j->axis.x, j->axis.y, j->axis.z) << "\n";
        if (j->type != urdf::Joint::CONTINUOUS && j->limits)
          joints << "    limits: [" << num(j->limits->lower) << ", " << num(j->limits->upper) << "]\n";
      }
      if (j->mimic) joints << "    # mimics " << j->mimic->joint_name << " in the URDF: checked as independent\n";
      frame_of[j->child_link_name] = j->name;
      const urdf::LinkConstSharedPtr child = urdf->getLink(j->child_link_name);
      if (child) queue.push_back(child);
    }
  }
  int fitted = 0, with_geometry = 0;
  for (const auto& link : order)
    if (!link->collision_array.empty()) ++with_geometry;
  for (const auto& link : order) {
    if (link->collision_array.empty()) continue;
    const Part part = linkPart(path, *link, options);
    if (part.empty()) continue;
    FitOptions fo;
    fo.points = options.points;
    if (options.progress)
      fo.progress = [&](double f) { options.progress((fitted + f) / std::max(1, with_geometry)); };
    const FitResult fit_result = fit(part, fo);
    bodies << "  - name: " << link->name << "\n"
           << "    frame: " << frame_of.at(link->name) << "\n"
           << "    points: " << flowPoints(fit_result.points) << "\n"
           << "    radius: " << yamlNumber(fit_result.radius, true) << "   # volume " << num(fit_result.volume)
           << " m^3, hull " << num(fit_result.hull_volume) << " m^3\n";
    body_names.insert(link->name);
    ++fitted;
  }
  std::vector<std::array<std::string, 2>> ignore;
  if (!options.srdf.empty()) ignore = readSrdf(srdf, options.srdf, link_names, body_names);

  std::ostringstream out;
  out << "# Imported from " << std::filesystem::path(path).filename().string()
      << (options.srdf.empty() ? "" : " and " + std::filesystem::path(options.srdf).filename().string())
      << " by kccd import (" << options.points << " core points per link)\n"
      << "kccd: 1\n"
      << "name: " << urdf->getName() << "\n"
      << "safety_margin: " << num(options.safety_margin) << "\n";
  const std::string jt = joints.str(), bt = bodies.str();
  out << "joints:" << (jt.empty() ? " []\n" : "\n" + jt);
  out << "bodies:" << (bt.empty() ? " []\n" : "\n" + bt);
  out << "pairs:\n  check: all\n  ignore: " << flowPairs(ignore, 11) << "\n";
  const std::string text = out.str();
  try {
    (void)parseModel(text, path + " (imported)");
  } catch (const ModelError& e) {
    throw std::runtime_error(std::string("the imported model does not load: ") + e.what());
  }
  if (options.progress) options.progress(1.0);
  return text;
}

}  // namespace kccd::modelling
