#include "kccd/modelling/part.hpp"

#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/SVD>

#include "kccd/hull/sphere_polytope.hpp"

namespace kccd::modelling {
namespace {

constexpr int kCircleSides = 128;  // circumscribed polygon: overestimates a circle by 0.03 %

const hull::Icosphere& unitIcosphere() {
  static const hull::Icosphere sphere = hull::icosphere(2);  // 162 vertices
  return sphere;
}

// A circle of `radius` in the local xz plane at height y, covered from outside.
void addCircle(Part& part, const Eigen::Affine3d& transform, double radius, double y) {
  const double r = radius / std::cos(std::numbers::pi / kCircleSides) * (1.0 + 1e-12);
  for (int i = 0; i < kCircleSides; ++i) {
    const double a = 2.0 * std::numbers::pi * i / kCircleSides;
    part.points.push_back(transform * Vec3(r * std::cos(a), y, r * std::sin(a)));
  }
}

}  // namespace

const std::vector<Vec3>& circumscribedUnitSphere() {
  static const std::vector<Vec3> vertices = hull::circumscribedVertices(unitIcosphere());
  return vertices;
}

std::vector<Vec3> Part::samples(int per_ball) const {
  std::vector<Vec3> out = points;
  const hull::Icosphere& s = unitIcosphere();
  const int n = std::min<int>(per_ball, static_cast<int>(s.vertices.size()));
  for (const Sphere& b : balls)
    for (int i = 0; i < n; ++i) out.push_back(b.center + b.radius * s.vertices[i]);
  return out;
}

void Part::addSphere(const Eigen::Affine3d& transform, double radius) {
  ++primitives;
  const Eigen::Matrix3d a = transform.linear();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a);
  const Vec3 sv = svd.singularValues();
  if (sv(2) >= sv(0) * (1.0 - 1e-9)) {  // a similarity: still a ball (largest stretch taken)
    balls.push_back({transform.translation(), radius * sv(0) * (1.0 + 1e-12)});
    return;
  }
  for (const Vec3& v : circumscribedUnitSphere()) points.push_back(transform * (radius * v));
}

void Part::addCylinderY(const Eigen::Affine3d& transform, double radius, double height) {
  ++primitives;
  addCircle(*this, transform, radius, -height / 2);
  addCircle(*this, transform, radius, height / 2);
}

void Part::addConeY(const Eigen::Affine3d& transform, double bottom_radius, double height) {
  ++primitives;
  addCircle(*this, transform, bottom_radius, -height / 2);
  points.push_back(transform * Vec3(0, height / 2, 0));
}

void Part::addBox(const Eigen::Affine3d& transform, const Vec3& size) {
  ++primitives;
  for (int i = 0; i < 8; ++i)
    points.push_back(transform * Vec3((i & 1 ? 0.5 : -0.5) * size.x(), (i & 2 ? 0.5 : -0.5) * size.y(),
                                      (i & 4 ? 0.5 : -0.5) * size.z()));
}

void Part::addTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const int n = static_cast<int>(points.size());
  points.insert(points.end(), {a, b, c});
  faces.push_back({n, n + 1, n + 2});
  ++triangles;
}

void Part::append(const Part& other) {
  const int offset = static_cast<int>(points.size());
  for (const auto& f : other.faces) faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  points.insert(points.end(), other.points.begin(), other.points.end());
  balls.insert(balls.end(), other.balls.begin(), other.balls.end());
  triangles += other.triangles;
  primitives += other.primitives;
  coordinate_guard = std::max(coordinate_guard, other.coordinate_guard);
}

}  // namespace kccd::modelling
