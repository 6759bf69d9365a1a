// Penetration depth and an independent intersection test, both through libccd.
#include <ccd/ccd.h>
#include <ccd/vec3.h>

#include "kccd/distance.hpp"

namespace kccd {
namespace {

void sschSupport(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto& s = *static_cast<const SschView*>(obj);
  const Vec3 d(ccdVec3X(dir), ccdVec3Y(dir), ccdVec3Z(dir));
  const Vec3* best = &s.points[0];
  double best_dot = best->dot(d);
  for (const Vec3& p : s.points) {
    const double dot = p.dot(d);
    if (dot > best_dot) {
      best_dot = dot;
      best = &p;
    }
  }
  const double n = d.norm();
  const Vec3 q = n > 0.0 ? Vec3(*best + (s.radius / n) * d) : *best;
  ccdVec3Set(out, q.x(), q.y(), q.z());
}

void sschCenter(const void* obj, ccd_vec3_t* out) {
  const auto& s = *static_cast<const SschView*>(obj);
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : s.points) c += p;
  c /= static_cast<double>(s.points.size());
  ccdVec3Set(out, c.x(), c.y(), c.z());
}

ccd_t makeCcd() {
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = sschSupport;
  ccd.support2 = sschSupport;
  ccd.center1 = sschCenter;
  ccd.center2 = sschCenter;
  ccd.max_iterations = 500;
  ccd.mpr_tolerance = 1e-12;
  ccd.epa_tolerance = 1e-12;
  return ccd;
}

}  // namespace

Penetration penetration(const SschView& a, const SschView& b) {
  Penetration out;
  if (a.points.empty() || b.points.empty()) return out;
  ccd_t ccd = makeCcd();
  ccd_real_t depth = 0.0;
  ccd_vec3_t dir, pos;
  if (ccdMPRPenetration(&a, &b, &ccd, &depth, &dir, &pos) == 0) {
    out.overlapping = true;
    out.depth = depth;
    out.direction = Vec3(ccdVec3X(&dir), ccdVec3Y(&dir), ccdVec3Z(&dir));
    out.position = Vec3(ccdVec3X(&pos), ccdVec3Y(&pos), ccdVec3Z(&pos));
  }
  return out;
}

bool intersectsLibccd(const SschView& a, const SschView& b) {
  if (a.points.empty() || b.points.empty()) return true;
  ccd_t ccd = makeCcd();
  return ccdGJKIntersect(&a, &b, &ccd) != 0;
}

}  // namespace kccd
