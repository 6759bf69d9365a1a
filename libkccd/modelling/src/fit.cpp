#include "kccd/modelling/fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include "fit_seeds.hpp"
#include "kccd/distance.hpp"
#include "kccd/hull/principal.hpp"
#include "kccd/modelling/convex_hull.hpp"
#include "kccd/modelling/yaml_edit.hpp"

namespace kccd::modelling {
namespace {

using detail::centroid;
using detail::farthestPoints;
using detail::greatestHull;
using detail::kMeans;
using detail::offsetClouds;
using detail::vertexNormals;

constexpr int kMaxConstraintPoints = 384;

// Distance from x to conv(core): an upper bound (the closest point found lies in the hull).
double hullDistanceUpper(const Vec3& x, std::span<const Vec3> core) {
  const DistanceResult d = distance(SschView{std::span<const Vec3>(&x, 1), 0.0}, SschView{core, 0.0});
  return d.hull_upper;
}

// What the optimiser must cover: hull vertices (reduced to extreme points) and balls.
struct Constraints {
  std::vector<Vec3> points;
  std::vector<Sphere> balls;
  double diameter = 0.0;
  Vec3 center = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // principal axes of the part
};

std::vector<Vec3> fibonacciDirections(int n) {
  std::vector<Vec3> d;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(1.0 - z * z);
    d.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return d;
}

class Objective {
 public:
  explicit Objective(const Constraints& c)
      : c_(c), directions_(c.points.size() + c.balls.size(), Vec3::UnitX()), last_worst_(0) {}

  double radius(std::span<const Vec3> core) {
    double r = 0.0;
    auto consider = [&](std::size_t index, const Vec3& x, double grow) {
      double cheap = std::numeric_limits<double>::infinity();  // distance to the nearest core point
      for (const Vec3& p : core) cheap = std::min(cheap, (x - p).squaredNorm());
      if (std::sqrt(cheap) + grow <= r) return false;
      GjkOptions o = options_;
      o.warm_start = &directions_[index];  // the last direction: one step moves little
      const DistanceResult d = distance(SschView{std::span<const Vec3>(&x, 1), 0.0}, SschView{core, 0.0}, o);
      directions_[index] = d.direction;
      const double v = d.hull_upper + grow;
      if (v > r) {
        r = v;
        return true;
      }
      return false;
    };
    if (last_worst_ < c_.points.size()) consider(last_worst_, c_.points[last_worst_], 0.0);
    for (std::size_t i = 0; i < c_.points.size(); ++i)
      if (consider(i, c_.points[i], 0.0)) last_worst_ = i;
    for (std::size_t i = 0; i < c_.balls.size(); ++i)
      consider(c_.points.size() + i, c_.balls[i].center, c_.balls[i].radius);
    return r;
  }

  double operator()(std::span<const Vec3> core) {
    ++evaluations;
    return convexHull(core).sschVolume(radius(core));
  }

  int evaluations = 0;

 private:
  const Constraints& c_;
  std::vector<Vec3> directions_;
  std::size_t last_worst_;
  // The optimiser compares volumes only; the final radius is computed exactly elsewhere.
  GjkOptions options_{.max_iterations = 64, .relative_tolerance = 1e-7};
};

// The part's hull for measuring how far a volume reaches outside it: planes of its faces
// (solids) and its vertices. Built on the part's points and points on its balls' surfaces.
struct OutsideHull {
  std::vector<Vec3> vertices;
  std::vector<Vec3> normals;  // unit, outward
  std::vector<double> offsets;
  bool solid = false;
};

OutsideHull outsideHull(const Part& part) {
  OutsideHull o;
  const std::vector<Vec3> samples = part.samples(162);
  if (samples.empty()) return o;
  const ConvexHull h = convexHull(samples);
  for (int i : h.vertices) o.vertices.push_back(samples[i]);
  if (h.dimension == 3) {
    for (const auto& t : h.triangles) {
      const Vec3 n = (samples[t[1]] - samples[t[0]]).cross(samples[t[2]] - samples[t[0]]);
      if (!(n.norm() > 0.0)) continue;
      o.normals.push_back(n.normalized());
      o.offsets.push_back(o.normals.back().dot(samples[t[0]]));
    }
    o.solid = !o.normals.empty();
  }
  return o;
}

// Signed distance from x to the hull: the distance outside (an upper bound, through GJK), minus
// the depth inside (the distance to the nearest face plane: a ball of that radius lies inside).
double signedDistance(const Vec3& x, const OutsideHull& h) {
  if (h.solid) {
    double worst = -INFINITY;
    for (std::size_t f = 0; f < h.normals.size(); ++f) worst = std::max(worst, h.normals[f].dot(x) - h.offsets[f]);
    if (worst <= 0.0) return worst;
  }
  return hullDistanceUpper(x, h.vertices);
}

double outsideOf(std::span<const Vec3> core, double radius, const OutsideHull& h) {
  double worst = -INFINITY;
  for (const Vec3& p : core) worst = std::max(worst, signedDistance(p, h));
  return std::max(0.0, worst + radius);
}

// The part's points and its balls' circumscribed polytopes, with their hull: what an exact hull
// keeps and a simplified hull chooses from (balls lie inside their polytopes: only vertices to cover).
struct PolytopeHull {
  std::vector<Vec3> samples;
  ConvexHull hull;
};

PolytopeHull polytopeHull(const Part& part) {
  PolytopeHull p;
  p.samples = part.points;
  for (const Sphere& b : part.balls)
    for (const Vec3& v : circumscribedUnitSphere()) p.samples.push_back(b.center + b.radius * v);
  p.hull = convexHull(p.samples);
  return p;
}

// What a covering radius is measured against: the hull vertices of the part's points (the
// hull is computed once per part), its balls and its input rounding guard.
struct Cover {
  std::vector<Vec3> vertices;
  std::vector<Sphere> balls;
  double guard = 0.0;
};

Cover makeCover(const Part& part) {
  Cover c;
  if (!part.points.empty())
    for (int i : convexHull(part.points).vertices) c.vertices.push_back(part.points[i]);
  c.balls = part.balls;
  c.guard = part.coordinate_guard;
  return c;
}

double coverRadius(std::span<const Vec3> core, const Cover& cover) {
  double r = 0.0, scale = 0.0;
  for (const Vec3& p : core) scale = std::max(scale, p.cwiseAbs().maxCoeff());
  for (const Vec3& v : cover.vertices) {
    r = std::max(r, hullDistanceUpper(v, core));
    scale = std::max(scale, v.cwiseAbs().maxCoeff());
  }
  for (const Sphere& b : cover.balls) {
    r = std::max(r, hullDistanceUpper(b.center, core) + b.radius);
    scale = std::max(scale, b.center.cwiseAbs().maxCoeff() + b.radius);
  }
  if (!std::isfinite(r) || !std::isfinite(scale)) throw std::invalid_argument("the part has non-finite coordinates");
  // Rounding of the distance computation (a few ulps of the coordinates) and of the input.
  return r + 16.0 * std::numeric_limits<double>::epsilon() * scale + cover.guard;
}

Constraints buildConstraints(const Part& part, const Cover& cover, int& hull_vertex_count) {
  Constraints c;
  c.balls = cover.balls;
  c.points = cover.vertices;
  hull_vertex_count = static_cast<int>(c.points.size());
  if (c.points.size() > static_cast<std::size_t>(kMaxConstraintPoints)) {
    // Keep the extreme vertex in many directions; the final radius uses every vertex.
    std::vector<Vec3> kept;
    std::vector<char> used(c.points.size(), 0);
    for (const Vec3& d : fibonacciDirections(kMaxConstraintPoints)) {
      std::size_t best = 0;
      for (std::size_t i = 1; i < c.points.size(); ++i)
        if (c.points[i].dot(d) > c.points[best].dot(d)) best = i;
      if (!used[best]) used[best] = 1, kept.push_back(c.points[best]);
    }
    c.points = std::move(kept);
  }
  const std::vector<Vec3> all = part.samples(12);
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& v : all) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  c.center = (lo + hi) / 2.0;
  c.diameter = (hi - lo).norm();
  c.axes = hull::principalFrame(all).axes;
  return c;
}

std::vector<Vec3> scaled(const std::vector<Vec3>& core, const Vec3& center, double s) {
  std::vector<Vec3> out(core.size());
  for (std::size_t j = 0; j < core.size(); ++j) out[j] = center + s * (core[j] - center);
  return out;
}

// Best uniform shrink of a seed set towards `center` (golden-section search on the factor).
std::vector<Vec3> bestShrink(const std::vector<Vec3>& core, const Vec3& center, double hi, Objective& f,
                             double& value) {
  double a = 0.0, b = hi;
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = f(scaled(core, center, x1)), f2 = f(scaled(core, center, x2));
  for (int i = 0; i < 24; ++i) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = f(scaled(core, center, x1));
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = f(scaled(core, center, x2));
    }
  }
  const double s = f1 < f2 ? x1 : x2;
  value = std::min(f1, f2);
  return scaled(core, center, s);
}

// Pattern search in randomly rotated frames (a rotating frame avoids the stalls of a fixed
// compass on the ridges of a max function).
std::vector<Vec3> patternSearch(std::vector<Vec3> core, double value, const Constraints& c, Objective& f,
                                const FitOptions& options, std::mt19937_64& rng) {
  double step = 0.125 * c.diameter;
  const double min_step = 1e-6 * c.diameter;
  const int budget = options.max_evaluations;
  const int start = f.evaluations;
  std::normal_distribution<double> normal;
  int failures = 0, sweep = 0;
  while (step > min_step && f.evaluations - start < budget) {
    bool improved = false;
    Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
    // The part's principal frame on every other sweep, a random one in between.
    const Eigen::Matrix3d frame = sweep++ % 2 == 0 ? c.axes : q.normalized().toRotationMatrix();
    for (std::size_t j = 0; j < core.size(); ++j) {
      for (int axis = 0; axis < 3; ++axis) {
        for (double sign : {1.0, -1.0}) {
          std::vector<Vec3> trial = core;
          trial[j] += sign * step * frame.col(axis);
          double v = f(trial);
          if (v < value) {
            core = trial, value = v, improved = true;
            // Keep going while it pays.
            for (int k = 0; k < 4; ++k) {
              trial[j] += sign * step * frame.col(axis);
              v = f(trial);
              if (v >= value) break;
              core = trial, value = v;
            }
          }
        }
      }
    }
    // Collective moves: a single point rarely lowers the radius alone, but the whole set
    // scaled along one direction, or moved, often does.
    const Vec3 mean = centroid(core);
    const double rel = step / c.diameter * 2.0;
    auto collective = [&](const Eigen::Matrix3d& map, const Vec3& shift) {
      std::vector<Vec3> trial(core.size());
      for (std::size_t j = 0; j < core.size(); ++j) trial[j] = mean + map * (core[j] - mean) + shift;
      const double v = f(trial);
      if (v < value) core = trial, value = v, improved = true;
    };
    for (double sign : {-1.0, 1.0}) {
      collective(Eigen::Matrix3d::Identity() * (1.0 + sign * rel), Vec3::Zero());
      for (int axis = 0; axis < 3; ++axis) {
        const Vec3 d = frame.col(axis);
        collective(Eigen::Matrix3d::Identity() + sign * rel * d * d.transpose(), Vec3::Zero());
        collective(Eigen::Matrix3d::Identity(), sign * step * d);
      }
    }
    if (improved) {
      failures = 0;
    } else if (++failures >= 2) {
      step *= 0.5;
      failures = 0;
    }
    if (options.progress)
      options.progress(std::min(1.0, std::max(std::log(c.diameter / 8.0 / step) / std::log(c.diameter / 8.0 / min_step),
                                              double(f.evaluations - start) / budget)));
  }
  return core;
}

}  // namespace

double sschVolume(std::span<const Vec3> points, double radius) { return convexHull(points).sschVolume(radius); }

double coveringRadius(std::span<const Vec3> core, const Part& part) { return coverRadius(core, makeCover(part)); }

FitResult exactHull(const Part& part) {
  if (part.empty()) throw std::invalid_argument("the part has no geometry");
  const PolytopeHull p = polytopeHull(part);
  const ConvexHull& h = p.hull;
  FitResult result;
  Cover cover;
  cover.guard = part.coordinate_guard;
  for (int i : h.vertices) cover.vertices.push_back(p.samples[i]);
  result.points = cover.vertices;
  for (Vec3& p : result.points)  // as printed; the radius below covers the rounding
    for (int i = 0; i < 3; ++i) p(i) = std::stod(yamlNumber(p(i)));
  result.radius = coverRadius(result.points, cover);
  result.volume = sschVolume(result.points, result.radius);
  result.hull_volume = convexHull(part.samples()).volume;
  result.hull_vertices = static_cast<int>(h.vertices.size());
  result.outside = outsideDistance(result.points, result.radius, part);
  result.method = "hull";
  return result;
}

namespace {

// fit() with the part's outside hull `h` (outsideHull) given: fitToTolerance has built it already.
FitResult fitWithHull(const Part& part, const FitOptions& options, const OutsideHull& h);

}  // namespace

FitResult fit(const Part& part, const FitOptions& options) { return fitWithHull(part, options, outsideHull(part)); }

namespace {

FitResult fitWithHull(const Part& part, const FitOptions& options, const OutsideHull& h) {
  if (options.points < 1 || options.points > kMaxCorePoints)
    throw std::invalid_argument("the number of core points must be 1 ... " + std::to_string(kMaxCorePoints) + " (got " +
                                std::to_string(options.points) + ")");
  if (part.empty()) throw std::invalid_argument("the part has no geometry");
  FitResult result;
  const Cover cover = makeCover(part);
  const Constraints c = buildConstraints(part, cover, result.hull_vertices);
  result.hull_volume = convexHull(part.samples()).volume;
  std::mt19937_64 rng(options.seed);

  std::vector<Vec3> pool = c.points;
  for (const Sphere& b : c.balls) pool.push_back(b.center);

  std::vector<std::vector<Vec3>> extra_seeds(2);  // whole seeds, used as they are
  // Offset hulls at rounding radii from 2 % to 45 % of the part's thinnest principal extent.
  std::vector<std::vector<Vec3>> offsets;
  if (!c.points.empty()) {
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (const Vec3& p : c.points) {
      const Vec3 q = c.axes.transpose() * p;
      lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    }
    const double thin = (hi - lo).minCoeff();
    std::vector<double> radii;
    for (double f : {0.02, 0.05, 0.1, 0.15, 0.22, 0.3, 0.45}) radii.push_back(f * thin);
    offsets = offsetClouds(c.points, radii);
  }
  auto optimise = [&](int k, const FitOptions& opt) {
    Objective f(c);
    std::vector<std::vector<Vec3>> seeds;
    const std::vector<Vec3> fps = farthestPoints(pool, c.center, k);
    seeds.push_back(fps);
    if (k > 1 && static_cast<int>(pool.size()) > k) seeds.push_back(kMeans(pool, fps));
    // Seeds from the offset hulls (k of their points spread out, clustered, or spanning the
    // largest hull), refined in addition to the others.
    std::vector<std::vector<Vec3>> offset_seeds;
    if (k >= 3)
      for (const std::vector<Vec3>& cloud : offsets) {
        if (static_cast<int>(cloud.size()) < k) continue;
        const std::vector<Vec3> spread = farthestPoints(cloud, centroid(cloud), k);
        offset_seeds.push_back(spread);
        offset_seeds.push_back(kMeans(cloud, spread));
        offset_seeds.push_back(greatestHull(cloud, k));
      }
    if (k > 1) {
      // Corners of the principal box, flattened along its thinnest axes when k is small.
      Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
      for (const Vec3& p : pool) {
        const Vec3 q = c.axes.transpose() * p;
        lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
      }
      const int dims = k >= 8 ? 3 : k >= 4 ? 2 : 1;  // the axes are sorted by increasing spread
      std::vector<Vec3> corners;
      for (int i = 0; i < (1 << dims); ++i) {
        Vec3 q = (lo + hi) / 2;
        for (int d = 0; d < dims; ++d) q(2 - d) = i & (1 << d) ? hi(2 - d) : lo(2 - d);
        corners.push_back(c.axes * q);
      }
      std::vector<Vec3> seed = farthestPoints(corners, c.axes * ((lo + hi) / 2), std::min<int>(k, corners.size()));
      while (static_cast<int>(seed.size()) < k) seed.push_back(seed[seed.size() % corners.size()]);
      seeds.push_back(seed);
    }
    // Every seed shrunk to its best scale; the three best of the first seeds and the two best
    // offset seeds are refined (those with half the budget), the best result wins.
    using Start = std::pair<double, std::vector<Vec3>>;
    auto shrunk = [&](const std::vector<std::vector<Vec3>>& list) {
      std::vector<Start> out;
      for (const auto& s : list) {
        double v = 0.0;
        std::vector<Vec3> scaled_seed = bestShrink(s, centroid(s), 1.5, f, v);
        out.emplace_back(v, std::move(scaled_seed));
      }
      return out;
    };
    std::vector<Start> starts = shrunk(seeds);
    for (const auto& s : extra_seeds)
      if (static_cast<int>(s.size()) == k) starts.emplace_back(f(s), s);
    const auto by_value = [](const Start& x, const Start& y) { return x.first < y.first; };
    std::sort(starts.begin(), starts.end(), by_value);
    starts.resize(std::min<std::size_t>(3, starts.size()));
    const std::size_t first_offset = starts.size();
    std::vector<Start> offset_starts = shrunk(offset_seeds);
    std::sort(offset_starts.begin(), offset_starts.end(), by_value);
    for (std::size_t i = 0; i < std::min<std::size_t>(2, offset_starts.size()); ++i) starts.push_back(offset_starts[i]);
    const int runs = static_cast<int>(starts.size());
    FitOptions share = opt;  // each run gets the whole budget
    std::vector<Vec3> best;
    double best_value = INFINITY;
    for (int i = 0; i < runs; ++i) {
      if (opt.progress) share.progress = [&, i](double x) { opt.progress((i + x) / runs); };
      // Offset seeds start close to a good shape: half the budget each.
      share.max_evaluations =
          static_cast<std::size_t>(i) < first_offset ? opt.max_evaluations : opt.max_evaluations / 2;
      std::vector<Vec3> refined = patternSearch(starts[i].second, starts[i].first, c, f, share, rng);
      const double v = f(refined);
      if (v < best_value) best = std::move(refined), best_value = v;
    }
    result.evaluations += f.evaluations;
    return best;
  };

  // Baselines: the smallest enclosing sphere found, and the capsule on the principal axis.
  FitOptions quick = options;
  quick.progress = nullptr;
  quick.max_evaluations = 600;
  const std::vector<Vec3> centre = optimise(1, quick);
  result.sphere_volume = sschVolume(centre, coverRadius(centre, cover));

  const std::vector<Vec3> samples = part.samples(42);
  const hull::PrincipalFrame pca = hull::principalFrame(samples);
  const Vec3& mean = pca.mean;
  result.capsule_volume = INFINITY;
  std::vector<Vec3> capsule;
  for (int k = 0; k < 3; ++k) {  // the best of the three principal axes
    const Vec3 axis = pca.axes.col(k);
    double rad = 0.0;
    for (const Vec3& p : samples) rad = std::max(rad, ((p - mean) - axis * axis.dot(p - mean)).norm());
    double a = INFINITY, b = -INFINITY;  // segment [a, b] along the axis covering every sample
    for (const Vec3& p : samples) {
      const double t = axis.dot(p - mean);
      const double d = ((p - mean) - axis * t).norm();
      const double h = std::sqrt(std::max(0.0, rad * rad - d * d));
      a = std::min(a, t + h);
      b = std::max(b, t - h);
    }
    if (a > b) a = b = (a + b) / 2.0;
    const std::vector<Vec3> segment{mean + a * axis, mean + b * axis};
    const double v = sschVolume(segment, coverRadius(segment, cover));
    if (v < result.capsule_volume) result.capsule_volume = v, capsule = segment;
  }
  // The K points then start from the baselines too, so they never do worse than them.
  for (int j = 0; j < options.points; ++j) {
    const double t = options.points == 1 ? 0.5 : double(j) / (options.points - 1);
    extra_seeds[0].push_back(capsule[0] + t * (capsule[1] - capsule[0]));
    extra_seeds[1].push_back(centre[0]);
  }
  result.points = optimise(options.points, options);
  // The points as they will be printed (10 significant digits), the radius exactly for those.
  for (Vec3& p : result.points)
    for (int i = 0; i < 3; ++i) p(i) = std::stod(yamlNumber(p(i)));
  result.radius = coverRadius(result.points, cover);
  result.volume = sschVolume(result.points, result.radius);
  result.outside = outsideOf(result.points, result.radius, h);
  if (options.progress) options.progress(1.0);
  return result;
}

}  // namespace

double outsideDistance(std::span<const Vec3> core, double radius, const Part& part) {
  return outsideOf(core, radius, outsideHull(part));
}

namespace {

// The simplified hull at depth rho: each hull vertex (balls by their circumscribed polytopes) has
// a candidate core point, the vertex moved inwards by rho along its angle-weighted normal; the
// candidates of the vertices farthest from the kept points' hull are added one at a time until
// the volume (radius: the covering radius) reaches at most `tolerance` outside the part's hull
// H, or every candidate is in. rho = 0 keeps hull vertices (a radius of about the tolerance); a
// larger rho trades depth for a larger radius, and on rounded parts for far fewer points.
// `normal`: vertexNormals of the polytope hull's samples (empty unless it is solid).
FitResult simplifiedHull(const Part& part, const PolytopeHull& polytope, const std::vector<Vec3>& normal,
                         const OutsideHull& h, double tolerance, double rho) {
  const ConvexHull& hull = polytope.hull;
  Cover cover;
  cover.guard = part.coordinate_guard;
  for (int i : hull.vertices) cover.vertices.push_back(polytope.samples[i]);
  const std::vector<Vec3>& vertex = cover.vertices;
  const std::size_t n = vertex.size();
  std::vector<Vec3> candidate = vertex;
  if (rho > 0.0 && !normal.empty())
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& nv = normal[hull.vertices[i]];
      if (nv.norm() > 0.0) candidate[i] = vertex[i] - rho * nv.normalized();
    }
  for (Vec3& p : candidate)
    for (int a = 0; a < 3; ++a) p(a) = std::stod(yamlNumber(p(a)));  // as printed
  std::vector<double> depth(n);                                      // signed distance of each candidate to H
  for (std::size_t i = 0; i < n; ++i) depth[i] = signedDistance(candidate[i], h);
  FitResult result;
  result.hull_vertices = static_cast<int>(n);
  result.method = "simplified hull";
  std::vector<Vec3> core;
  std::vector<char> used(n, 0);
  double worst_depth = -INFINITY;
  auto take = [&](std::size_t i) {
    used[i] = 1;
    core.push_back(candidate[i]);
    worst_depth = std::max(worst_depth, depth[i]);
  };
  // Four spread-out vertices: the farthest from the centroid, then each farthest from those.
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : vertex) mean += p;
  mean /= static_cast<double>(std::max<std::size_t>(n, 1));
  std::vector<double> nearest(n, INFINITY);
  std::size_t next = 0;
  for (std::size_t i = 0; i < n; ++i)
    if ((vertex[i] - mean).squaredNorm() > (vertex[next] - mean).squaredNorm()) next = i;
  for (int k = 0; k < 4 && k < static_cast<int>(n); ++k) {
    take(next);
    for (std::size_t i = 0; i < n; ++i) nearest[i] = std::min(nearest[i], (vertex[i] - vertex[next]).squaredNorm());
    next = static_cast<std::size_t>(std::max_element(nearest.begin(), nearest.end()) - nearest.begin());
    if (used[next]) break;
  }
  // Then the candidate of the vertex farthest from the kept points' hull while that distance
  // (the radius) plus the shallowest kept point's signed distance exceeds the tolerance. A
  // vertex's distance only falls as the hull grows: one within the best-known distance is not
  // measured again.
  std::vector<double> d(n, INFINITY);
  std::vector<Vec3> directions(n, Vec3::UnitX());
  const GjkOptions options{.max_iterations = 64, .relative_tolerance = 1e-9};
  const double aim = 0.98 * tolerance;  // room for the exact radius's rounding guard
  while (true) {
    double far = -1.0;
    std::size_t pick = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (d[i] <= far) continue;
      GjkOptions o = options;
      o.warm_start = &directions[i];
      const DistanceResult r = distance(SschView{std::span<const Vec3>(&vertex[i], 1), 0.0}, SschView{core, 0.0}, o);
      directions[i] = r.direction;
      d[i] = r.hull_upper;
      if (d[i] > far) far = d[i], pick = i;
    }
    if (pick == n || far + worst_depth <= aim) break;
    if (used[pick]) {  // its own candidate is in and it is still too far: the depth is too deep
      std::size_t other = n;
      for (std::size_t i = 0; i < n; ++i)
        if (!used[i] && (other == n || d[i] > d[other])) other = i;
      if (other == n) break;
      pick = other;
    }
    take(pick);
  }
  result.points = core;
  result.radius = coverRadius(result.points, cover);
  result.volume = sschVolume(result.points, result.radius);
  result.hull_volume = hull.dimension == 3 ? hull.volume : 0.0;
  result.outside = outsideOf(result.points, result.radius, h);
  return result;
}

// The fewest points meeting the tolerance over depths from 0 to 45 % of the part's thinnest
// extent (ties: the smaller volume).
FitResult bestSimplifiedHull(const Part& part, const OutsideHull& h, double tolerance) {
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  const Eigen::Matrix3d axes = hull::principalFrame(h.vertices).axes;
  for (const Vec3& p : h.vertices) {
    const Vec3 q = axes.transpose() * p;
    lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  const double thin = h.vertices.empty() ? 0.0 : (hi - lo).minCoeff();
  std::vector<double> depths{0.0};
  for (double f : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0})
    if (f * tolerance < 0.45 * thin) depths.push_back(f * tolerance);
  for (double f : {0.1, 0.2, 0.3, 0.45}) depths.push_back(f * thin);
  const PolytopeHull polytope = polytopeHull(part);
  const std::vector<Vec3> normal =
      polytope.hull.dimension == 3 ? vertexNormals(polytope.samples, polytope.hull) : std::vector<Vec3>{};
  FitResult best;
  bool have = false;
  for (const double rho : depths) {
    FitResult r = simplifiedHull(part, polytope, normal, h, tolerance, rho);
    const bool meets = r.outside <= tolerance;
    const bool best_meets = have && best.outside <= tolerance;
    if (!have || (meets && !best_meets) ||
        (meets == best_meets &&
         (r.points.size() < best.points.size() || (r.points.size() == best.points.size() && r.volume < best.volume))))
      best = std::move(r), have = true;
  }
  return best;
}

}  // namespace

FitResult fitToTolerance(const Part& part, double tolerance, const FitOptions& options) {
  if (!(tolerance > 0.0) || !std::isfinite(tolerance))
    throw std::invalid_argument("the tolerance must be a positive length (got " + yamlNumber(tolerance) + ")");
  if (part.empty()) throw std::invalid_argument("the part has no geometry");
  const OutsideHull h = outsideHull(part);
  FitResult hull = bestSimplifiedHull(part, h, tolerance);
  if (hull.points.size() <= static_cast<std::size_t>(options.points) && hull.outside <= tolerance) {
    if (options.progress) options.progress(1.0);
    return hull;
  }
  FitResult fitted = fitWithHull(part, options, h);  // sets fitted.outside
  if (fitted.outside <= tolerance) return fitted;
  hull.evaluations = fitted.evaluations;
  hull.sphere_volume = fitted.sphere_volume;
  hull.capsule_volume = fitted.capsule_volume;
  return hull;
}

}  // namespace kccd::modelling
