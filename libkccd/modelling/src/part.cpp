#include "kccd/modelling/part.hpp"

#include <array>
#include <cmath>
#include <map>
#include <numbers>

#include <Eigen/SVD>

namespace kccd::modelling {
namespace {

constexpr int kCircleSides = 128;  // circumscribed polygon: overestimates a circle by 0.03 %

struct Icosphere {
  std::vector<Vec3> vertices;                 // on the unit sphere
  std::vector<std::array<int, 3>> faces;
};

Icosphere makeIcosphere(int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Icosphere s;
  s.vertices = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& v : s.vertices) v.normalize();
  s.faces = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
             {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      s.vertices.push_back((s.vertices[a] + s.vertices[b]).normalized());
      const int index = static_cast<int>(s.vertices.size()) - 1;
      mid.emplace(key, index);
      return index;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : s.faces) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    s.faces = std::move(next);
  }
  return s;
}

const Icosphere& unitIcosphere() {
  static const Icosphere sphere = makeIcosphere(2);  // 162 vertices
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
  static const std::vector<Vec3> vertices = [] {
    const Icosphere& s = unitIcosphere();
    // Scale so that every face plane lies at distance >= 1 from the centre.
    double min_distance = 1.0;
    for (const auto& f : s.faces) {
      const Vec3 n = (s.vertices[f[1]] - s.vertices[f[0]]).cross(s.vertices[f[2]] - s.vertices[f[0]]).normalized();
      min_distance = std::min(min_distance, std::abs(n.dot(s.vertices[f[0]])));
    }
    std::vector<Vec3> out;
    for (const Vec3& v : s.vertices) out.push_back(v * (1.0 / min_distance) * (1.0 + 1e-12));
    return out;
  }();
  return vertices;
}

std::vector<Vec3> Part::samples(int per_ball) const {
  std::vector<Vec3> out = points;
  const Icosphere& s = unitIcosphere();
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

void Part::append(const Part& other) {
  points.insert(points.end(), other.points.begin(), other.points.end());
  balls.insert(balls.end(), other.balls.begin(), other.balls.end());
  triangles += other.triangles;
  primitives += other.primitives;
  coordinate_guard = std::max(coordinate_guard, other.coordinate_guard);
}

}  // namespace kccd::modelling
