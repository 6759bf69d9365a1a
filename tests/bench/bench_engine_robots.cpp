// The whole arm, on real robots at kccd import's defaults: the braking-box collision and distances
// queries over random 2-20 degree boxes (cold: a reset checker each time), next to FCL checking the
// same robot's collision meshes (BVH, OBBRSS) at one configuration, the box's centre: every link
// pair the model checks, forward kinematics included, in the same run and the same loop.
// Warm: 2,000 cycles of a robot moving on from the last centre, 10 degree boxes a quarter degree
// apart, each checker keeping its table across cycles.
// The margin is 5 mm, and each centre is clear of it by 5 mm (the model's own 20 mm would flag
// every Panda box: its links 5 and 7 stay within 20 mm of each other at every configuration).
// As a check of both, at every centre the model's static lower bound of each link pair must not
// exceed FCL's distance between the link's meshes (the volumes contain the meshes).
// The robots: the Panda and the xArm 7 of robots.hpp ($KCCD_REAL_ROBOTS; the KR5 and the WAM have
// a link pair within 10 mm at each of 100,000 random configurations, so no centre is clear).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>
#include <urdf_parser/urdf_parser.h>

#include "kccd/checker.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/modelling/pair_proof.hpp"
#include "kccd/modelling/part.hpp"
#include "robots.hpp"

namespace {

using namespace kccd;
using Clock = std::chrono::steady_clock;
namespace km = kccd::modelling;
using Mesh = fcl::BVHModel<fcl::OBBRSSd>;
constexpr double kDeg = 3.141592653589793 / 180.0;
constexpr double kMargin = 0.005;

// A link's collision meshes as one BVH in the link's frame, and the frame the model puts it in.
struct Link {
  int frame = kWorld;
  std::shared_ptr<Mesh> mesh;
  int triangles = 0;
};

struct Arm {
  std::vector<Link> links;
  std::vector<std::pair<int, int>> pairs;  // link indices: every link pair the model checks
  std::map<std::string, int> link_index;
};

std::string meshFile(const std::string& urdf, const std::string& uri, const std::map<std::string, std::string>& pkgs) {
  namespace fs = std::filesystem;
  if (uri.rfind("package://", 0) == 0) {
    const std::string rest = uri.substr(10);
    const std::size_t slash = rest.find('/');
    return (fs::path(pkgs.at(rest.substr(0, slash))) / rest.substr(slash + 1)).string();
  }
  if (uri.rfind("file://", 0) == 0) return uri.substr(7);
  return fs::path(uri).is_absolute() ? uri : (fs::path(urdf).parent_path() / uri).string();
}

// The two links' indices in order, when both have meshes and they differ.
std::optional<std::pair<int, int>> linkPair(const Arm& a, const std::string& x, const std::string& y) {
  const auto ix = a.link_index.find(x), iy = a.link_index.find(y);
  if (ix == a.link_index.end() || iy == a.link_index.end() || ix->second == iy->second) return std::nullopt;
  return std::minmax(ix->second, iy->second);
}

// The URDF's collision meshes per link (the four robots' collision geometry is all meshes).
const Arm& arm(const std::string& robot) {
  static std::map<std::string, Arm> cache;
  Arm& a = cache[robot];
  if (!a.links.empty()) return a;
  const bench::Robot r = bench::robotNamed(robot);
  const Model& model = bench::importedModel(robot, bench::kDefault);
  const urdf::ModelInterfaceSharedPtr u = urdf::parseURDFFile(r.urdf);
  for (const auto& [name, link] : u->links_) {
    Link l;
    const auto body =
        std::find_if(model.bodies.begin(), model.bodies.end(), [&](const Body& b) { return b.linkName() == name; });
    if (body == model.bodies.end()) continue;  // no geometry, so no body
    l.frame = body->frame;
    l.mesh = std::make_shared<Mesh>();
    l.mesh->beginModel();
    for (const urdf::CollisionSharedPtr& c : link->collision_array) {
      if (!c || !c->geometry || c->geometry->type != urdf::Geometry::MESH) continue;
      const auto& m = static_cast<const urdf::Mesh&>(*c->geometry);
      const km::Part part = km::readPart(meshFile(r.urdf, m.filename, r.packages),
                                         {.merge = true, .scale = Vec3(m.scale.x, m.scale.y, m.scale.z)});
      const urdf::Pose& o = c->origin;
      Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
      t.translation() = Vec3(o.position.x, o.position.y, o.position.z);
      t.linear() = Eigen::Quaterniond(o.rotation.w, o.rotation.x, o.rotation.y, o.rotation.z).toRotationMatrix();
      for (const auto& f : part.faces) {
        l.mesh->addTriangle(t * part.points[f[0]], t * part.points[f[1]], t * part.points[f[2]]);
        ++l.triangles;
      }
    }
    l.mesh->endModel();
    if (l.triangles == 0) continue;
    a.link_index[name] = static_cast<int>(a.links.size());
    a.links.push_back(std::move(l));
  }
  std::set<std::pair<int, int>> pairs;
  for (const BodyPair& p : model.pairs)
    if (const auto lp = linkPair(a, model.bodies[p.a].linkName(), model.bodies[p.b].linkName())) pairs.insert(*lp);
  a.pairs.assign(pairs.begin(), pairs.end());
  return a;
}

std::vector<fcl::Transform3d> linkPoses(const Model& model, const Arm& a, const std::vector<double>& q,
                                        std::vector<Pose>& poses) {
  framePoses(model, q, poses);
  std::vector<fcl::Transform3d> out;
  out.reserve(a.links.size());
  for (const Link& l : a.links) out.emplace_back(framePose(poses, l.frame).matrix());
  return out;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(p * static_cast<double>(v.size())))];
}

void BM_WholeArm(benchmark::State& state, const char* robot) {
  if (!bench::robotNamed(robot).found()) {
    state.SkipWithError("robot not found (dart-doc, or $KCCD_REAL_ROBOTS)");
    return;
  }
  const Model& model = bench::importedModel(robot, bench::kDefault);
  const Arm& a = arm(robot);
  Checker checker(model);
  const auto ranges = km::jointRanges(model);
  auto range = [&](int s) {  // a state's limits; ±3 where it has none
    return std::pair{std::isnan(ranges[s][0]) ? -3.0 : ranges[s][0], std::isnan(ranges[s][1]) ? 3.0 : ranges[s][1]};
  };
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const QueryOptions collision{.type = QueryType::Collision, .margin = kMargin};
  const QueryOptions distances{.type = QueryType::Distances, .margin = kMargin};
  const QueryOptions clear_centre{.type = QueryType::Collision, .margin = 2.0 * kMargin};
  const QueryOptions statics{.type = QueryType::Distances, .margin = kMargin, .exact_below = INFINITY};
  std::vector<double> t_col, t_dist, t_fcl_col, t_fcl_dist, t_col_warm, t_dist_warm;
  std::vector<double> centre_of_last;
  std::vector<Pose> poses(model.joints.size());
  long flagged = 0, fcl_contacts = 0, checked_pairs = 0, above_fcl = 0, rejected = 0;
  double tightest = INFINITY;
  auto seconds = [](auto&& f) {
    const auto t0 = Clock::now();
    f();
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  for (auto _ : state) {
    for (int box = 0; box < 200; ++box) {
      // A centre inside the limits whose static clearance exceeds the margin by 5 mm, and a
      // braking box of 2-20 degrees per revolute joint (2-20 mm per prismatic) around it.
      std::vector<double> q(static_cast<std::size_t>(model.stateSize())), lo, hi;
      for (int tries = 0;; ++tries) {
        for (int s = 0; s < model.stateSize(); ++s) {
          const auto [l, h] = range(s);
          q[s] = l + (h - l) * u(rng);
        }
        checker.reset();
        if (!checker.query(q, q, clear_centre).collision) break;
        if (tries == 100000) {
          state.SkipWithError("no centre clear of the margin in 100,000 tries");
          return;
        }
        ++rejected;
      }
      centre_of_last = q;
      lo = hi = q;
      for (const Joint& j : model.joints) {
        if (j.type != JointType::Revolute && j.type != JointType::Prismatic) continue;
        const double w = (2.0 + 18.0 * u(rng)) * (j.type == JointType::Revolute ? kDeg : 1e-3);
        lo[j.state_offset] -= 0.5 * w;
        hi[j.state_offset] += 0.5 * w;
      }
      auto mine = [&] {
        checker.reset();
        t_col.push_back(seconds([&] { flagged += checker.query(lo, hi, collision).collision; }));
        checker.reset();
        t_dist.push_back(seconds([&] { benchmark::DoNotOptimize(checker.query(lo, hi, distances).min_distance); }));
      };
      auto theirs = [&] {
        t_fcl_col.push_back(seconds([&] {
          const auto tf = linkPoses(model, a, q, poses);
          for (const auto& [i, j] : a.pairs) {
            fcl::CollisionRequestd request;
            fcl::CollisionResultd result;
            fcl_contacts +=
                fcl::collide(a.links[i].mesh.get(), tf[i], a.links[j].mesh.get(), tf[j], request, result) > 0;
          }
        }));
        t_fcl_dist.push_back(seconds([&] {
          const auto tf = linkPoses(model, a, q, poses);
          for (const auto& [i, j] : a.pairs) {
            fcl::DistanceRequestd request;
            fcl::DistanceResultd result;
            benchmark::DoNotOptimize(
                fcl::distance(a.links[i].mesh.get(), tf[i], a.links[j].mesh.get(), tf[j], request, result));
          }
        }));
      };
      if (box % 2 == 0) {
        mine();
        theirs();
      } else {
        theirs();
        mine();
      }
      // The check: per link pair, the model's static bound at the centre <= FCL's mesh distance.
      checker.reset();
      const QueryResult& r = checker.query(q, q, statics);
      const auto tf = linkPoses(model, a, q, poses);
      for (const auto& [names, b] : bench::linkDistances(model, r)) {
        const auto lp = linkPair(a, names.first, names.second);
        if (!lp) continue;
        const auto [i, j] = *lp;
        fcl::DistanceRequestd request;
        fcl::DistanceResultd result;
        const double mesh = fcl::distance(a.links[i].mesh.get(), tf[i], a.links[j].mesh.get(), tf[j], request, result);
        ++checked_pairs;
        if (mesh <= 0.0) continue;
        above_fcl += b > mesh + 1e-9;
        tightest = std::min(tightest, mesh - b);
      }
    }
    // Warm: a robot moving through the last centre, each cycle's box a quarter degree per joint
    // from the last, the checkers keeping their tables (what a controller calling every cycle pays).
    std::vector<double> q = centre_of_last, lo, hi;
    Checker warm_collision(model), warm_distances(model);
    for (int cycle = 0; cycle < 2000; ++cycle) {
      lo = hi = q;
      for (const Joint& j : model.joints) {
        if (j.type != JointType::Revolute && j.type != JointType::Prismatic) continue;
        const double step = (j.type == JointType::Revolute ? 0.25 * kDeg : 0.25e-3) * (u(rng) < 0.5 ? -1.0 : 1.0);
        const auto [l, h] = range(j.state_offset);
        q[j.state_offset] = std::clamp(q[j.state_offset] + step, l, h);
        const double w = 10.0 * (j.type == JointType::Revolute ? kDeg : 1e-3);
        lo[j.state_offset] = q[j.state_offset] - 0.5 * w;
        hi[j.state_offset] = q[j.state_offset] + 0.5 * w;
      }
      t_col_warm.push_back(
          seconds([&] { benchmark::DoNotOptimize(warm_collision.query(lo, hi, collision).collision); }));
      t_dist_warm.push_back(
          seconds([&] { benchmark::DoNotOptimize(warm_distances.query(lo, hi, distances).min_distance); }));
    }
  }
  int triangles = 0;
  for (const Link& l : a.links) triangles += l.triangles;
  int points = 0;
  for (const Body& b : model.bodies) points += static_cast<int>(b.points.size());
  state.counters["bodies"] = static_cast<double>(model.bodies.size());
  state.counters["points"] = points;
  state.counters["link_pairs"] = static_cast<double>(a.pairs.size());
  state.counters["triangles"] = triangles;
  // Median and 99.9th percentile (of 200 boxes: the largest) of each timing, in µs.
  const std::pair<const char*, const std::vector<double>*> timings[] = {
      {"collision", &t_col},           {"distances", &t_dist},
      {"warm_collision", &t_col_warm}, {"warm_distances", &t_dist_warm},
      {"fcl_collide", &t_fcl_col},     {"fcl_distance", &t_fcl_dist}};
  for (const auto& [name, t] : timings) {
    state.counters[std::string(name) + "_p50_us"] = 1e6 * percentile(*t, 0.5);
    state.counters[std::string(name) + "_p999_us"] = 1e6 * percentile(*t, 0.999);
  }
  state.counters["flagged_boxes"] = static_cast<double>(flagged) / static_cast<double>(t_col.size());
  state.counters["fcl_contacts"] = static_cast<double>(fcl_contacts);
  state.counters["bound_above_mesh"] = static_cast<double>(above_fcl);  // must be 0
  state.counters["pairs_checked_vs_mesh"] = static_cast<double>(checked_pairs);
  state.counters["tightest_mm"] = 1e3 * tightest;
  state.counters["centres_rejected"] = static_cast<double>(rejected);
}

}  // namespace

BENCHMARK_CAPTURE(BM_WholeArm, panda, "panda")->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WholeArm, xarm, "xarm")->Iterations(1)->Unit(benchmark::kMillisecond);
