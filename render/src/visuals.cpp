#include "kccd/render/visuals.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "kccd/input_error.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/modelling/part.hpp"
#include "kccd/render/ssch_mesh.hpp"

namespace kccd::render {
namespace {

void addQuad(std::vector<Vec3>& soup, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  soup.insert(soup.end(), {a, b, c, a, c, d});
}

// Triangles of a primitive centred at the origin (cylinders along z, as URDF has them).
std::vector<Vec3> primitive(const Visual& v) {
  std::vector<Vec3> soup;
  if (v.shape == Visual::Shape::Box) {
    const Vec3 h = 0.5 * v.size;
    auto corner = [&](int i) { return Vec3(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z()); };
    const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) addQuad(soup, corner(f[0]), corner(f[1]), corner(f[2]), corner(f[3]));
  } else if (v.shape == Visual::Shape::Cylinder) {
    const int n = 48;
    const double r = v.size.x(), h = 0.5 * v.size.z();
    for (int i = 0; i < n; ++i) {
      const double a0 = 2 * std::numbers::pi * i / n, a1 = 2 * std::numbers::pi * (i + 1) / n;
      const Vec3 p0(r * std::cos(a0), r * std::sin(a0), 0), p1(r * std::cos(a1), r * std::sin(a1), 0);
      const Vec3 top(0, 0, h);
      addQuad(soup, p0 - top, p1 - top, p1 + top, p0 + top);
      soup.insert(soup.end(), {top, p0 + top, p1 + top, -top, p1 - top, p0 - top});
    }
  } else {
    const SpherePolytope& s = spherePolytope(3);
    for (const auto& t : s.triangles)
      for (const std::uint32_t k : t) soup.push_back(v.size.x() * s.vertices[k]);
  }
  return soup;
}

}  // namespace

std::vector<LoadedVisual> loadVisuals(const Model& model) {
  std::vector<LoadedVisual> out;
  for (std::size_t i = 0; i < model.visuals.size(); ++i) {
    const Visual& v = model.visuals[i];
    const std::string what = "visuals[" + std::to_string(i) + "]";
    std::vector<Vec3> soup;
    if (v.shape == Visual::Shape::Mesh) {
      modelling::Part part;
      try {
        part = modelling::readPart(v.mesh, {.merge = true, .scale = v.scale});
      } catch (const InputError& e) {
        throw VisualError(what + ": " + e.what());
      }
      if (part.primitives > 0 || part.points.size() != 3 * static_cast<std::size_t>(part.triangles))
        throw VisualError(what + ": " + v.mesh +
                          ": only triangle meshes are drawn (use box, cylinder or sphere for primitives)");
      soup = std::move(part.points);
      // A mirroring scale turns the triangles inside out: wind them back.
      if (v.scale.prod() < 0.0)
        for (std::size_t t = 0; t + 2 < soup.size(); t += 3) std::swap(soup[t + 1], soup[t + 2]);
    } else {
      soup = primitive(v);
    }
    for (Vec3& p : soup) p = v.origin * p;
    LoadedVisual lv;
    lv.frame = v.frame;
    lv.mesh = std::make_shared<const Mesh>(surfaceMesh(soup));
    lv.colour = cv::Scalar(255 * v.colour[2], 255 * v.colour[1], 255 * v.colour[0]);
    for (std::size_t b = 0; b < model.bodies.size(); ++b)
      if (model.bodies[b].frame == v.frame) {
        lv.label = static_cast<int>(b) + 1;
        break;
      }
    out.push_back(std::move(lv));
  }
  return out;
}

std::vector<Volume> visualVolumes(const Model& model, std::span<const LoadedVisual> visuals,
                                  std::span<const double> state) {
  std::vector<Pose> poses(model.joints.size());
  if (!framePoses(model, state, poses)) return {};
  std::vector<Volume> out;
  out.reserve(visuals.size());
  for (const LoadedVisual& v : visuals) {
    Volume volume;
    volume.surface = v.mesh;
    volume.pose = framePose(poses, v.frame);
    volume.colour = v.colour;
    volume.mask_label = v.label;
    volume.status = SafetyStatus::NoState;
    out.push_back(std::move(volume));
  }
  return out;
}

}  // namespace kccd::render
