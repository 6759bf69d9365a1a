// `kccd synth MODEL -o DIR`: a synthetic recording with ground truth — the robot's visible
// geometry (shrunken, shaded volumes strictly inside its SSCHs) moving along a smooth trajectory
// with near-collisions and one real collision, in a room with AprilTags, seen through a
// distorting camera with blur and noise; plus the state log, the true camera, the intrinsics, the
// tag layout, per-frame masks and a JSON summary of the truth.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "cli_args.hpp"
#include "kccd/render/visuals.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/calib/tag_scene.hpp"
#include "kccd/checker.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

struct SynthArgs {
  std::string model, output, camera;
  double seconds = 5.0, fps = 25.0, log_rate = 125.0, time_offset = 0.137, shrink = 0.8;
  double blur = 0.7, noise = 2.5;
  int width = 1280, height = 720;
  std::uint64_t seed = 1;
  std::string codec = "ffv1";
  std::string appearance = "auto";  // auto, volumes, visuals
  bool no_collision = false, force = false, quiet = false;
  bool size_given = false;  // --width or --height on the command line
  bool shrink_given = false;  // --visible-scale on the command line
};

// ---------------------------------------------------------------------------------------------
// The trajectory: per state value a centre plus two sines, blended towards goal configurations
// by smooth bumps (events). Everything stays within the joint limits (convex blends of in-limit
// values).

struct Event {
  enum Kind { Near, Collision } kind = Near;
  double time = 0.0, half_width = 0.5, beta = 0.0;
  double plateau = 0.0;  // fraction of the half width held at the full blend
  std::vector<double> goal;
  double min_distance = 0.0;  // over the log samples in its window
};

struct Trajectory {
  std::vector<double> centre;
  std::vector<std::array<double, 6>> waves;  // amplitude, omega, phase (x2)
  std::vector<Event> events;

  void at(double t, std::span<double> q, std::span<double> qd) const {
    const std::size_t n = centre.size();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& w = waves[i];
      q[i] = centre[i] + w[0] * std::sin(w[1] * t + w[2]) + w[3] * std::sin(w[4] * t + w[5]);
      qd[i] = w[0] * w[1] * std::cos(w[1] * t + w[2]) + w[3] * w[4] * std::cos(w[4] * t + w[5]);
    }
    for (const Event& e : events) {
      const double x = (t - e.time) / e.half_width;
      if (!(std::abs(x) < 1.0) || e.beta == 0.0) continue;
      // b = beta S(u), S the smootherstep 6u^5 - 15u^4 + 10u^3 of u = (1 - |x|) / (1 - plateau)
      // clamped to 1: position, velocity and acceleration continuous, held at the top.
      const double u = std::min(1.0, (1.0 - std::abs(x)) / (1.0 - e.plateau));
      const double b = e.beta * u * u * u * (u * (6.0 * u - 15.0) + 10.0);
      const double du = u < 1.0 ? -(x > 0 ? 1.0 : -1.0) / ((1.0 - e.plateau) * e.half_width) : 0.0;
      const double db = e.beta * 30.0 * u * u * (u - 1.0) * (u - 1.0) * du;
      for (std::size_t i = 0; i < n; ++i) {
        const double base = q[i], base_d = qd[i];
        q[i] = (1.0 - b) * base + b * e.goal[i];
        qd[i] = (1.0 - b) * base_d + db * (e.goal[i] - base);
      }
    }
  }
};

// Position limits of every state value (3-DOF joints do not move: [0, 0]).
struct Limits {
  std::vector<double> lo, hi, amplitude;
};

Limits limitsOf(const Model& m) {
  Limits l;
  for (const Joint& j : m.joints) {
    for (int k = 0; k < j.dof; ++k) {
      double lo = 0, hi = 0, amp = 0;
      if (j.dof == 1) {
        const double free_range = j.type == JointType::Revolute ? M_PI : 0.3;
        lo = j.limits ? (*j.limits)[0] : -free_range;
        hi = j.limits ? (*j.limits)[1] : free_range;
        amp = j.type == JointType::Revolute ? 0.3 : 0.05;
      }
      l.lo.push_back(lo), l.hi.push_back(hi), l.amplitude.push_back(amp);
    }
  }
  return l;
}

// The smallest distance bound of the model at one configuration (+inf without pairs; -1 for an
// unsafe status).
struct DistanceProbe {
  const Model& model;
  Checker checker;
  explicit DistanceProbe(const Model& m) : model(m), checker(m) {}
  double operator()(std::span<const double> q, int* pair = nullptr) {
    checker.reset();  // every state on its own: the answer does not depend on the order of queries
    const QueryResult& r = checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    if (r.status != Status::Ok) return -1.0;
    if (pair) {
      *pair = -1;
      for (const PairDistance& p : r.pairs)
        if (p.distance == r.min_distance) *pair = p.pair;
    }
    return r.min_distance;
  }
};

// Searches the trajectory (see the command's help). Throws UsageError when none is found.
Trajectory searchTrajectory(const Model& m, const SynthArgs& a, double t0, double t1, double dt) {
  const int n = m.stateSize();
  const Limits lim = limitsOf(m);
  const double margin = m.safety_margin;
  const double near_target = margin > 0 ? 0.5 * margin : 0.01;
  std::mt19937_64 rng(a.seed * 0x9E3779B97F4A7C15ull + 1);
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0));
  };
  DistanceProbe probe(m);
  static const bool debug = std::getenv("KCCD_SYNTH_DEBUG") != nullptr;
  std::vector<double> q(n), qd(n);
  const int samples = static_cast<int>(std::ceil((t1 - t0) / dt)) + 1;
  auto minOver = [&](const Trajectory& tr, double from, double to) {
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < samples; ++k) {
      const double t = t0 + k * dt;
      if (t < from || t > to) continue;
      tr.at(t, q, qd);
      best = std::min(best, probe(q));
    }
    return best;
  };
  bool any_pair = !m.pairs.empty();
  if (!any_pair && !a.no_collision)
    throw UsageError(a.model + ": the model checks no body pair, so it cannot collide (use --no-collision)");

  // Event times: near, collision, near (a near one instead of the collision with --no-collision).
  const double span = a.seconds;
  // Bumps last at least half a second (a robot's pace), so a short recording has fewer of them.
  const double w = std::clamp(0.12 * span, 0.35, 0.9);
  std::vector<Event> plan;
  // The collision (or the middle near one) first; the others where they fit.
  for (const auto& [f, kind] :
       {std::pair{0.6, Event::Collision}, std::pair{0.25, Event::Near}, std::pair{0.87, Event::Near}}) {
    Event e;
    e.kind = a.no_collision ? Event::Near : kind;
    e.time = f * span;
    e.half_width = w;
    e.plateau = e.kind == Event::Near ? 0.3 : 0.1;
    bool fits = true;
    for (const Event& p : plan) fits = fits && std::abs(e.time - p.time) >= 2.0 * w;
    if (fits) plan.push_back(e);
  }
  std::sort(plan.begin(), plan.end(), [](const Event& x, const Event& y) { return x.time < y.time; });

  for (int attempt = 0; attempt < 40; ++attempt) {
    Trajectory tr;
    tr.centre.assign(n, 0.0);
    tr.waves.assign(n, {});
    for (int i = 0; i < n; ++i) {
      const double mid = 0.5 * (lim.lo[i] + lim.hi[i]);
      double c = (lim.lo[i] <= 0.0 && 0.0 <= lim.hi[i]) ? 0.0 : mid;
      if (attempt > 0) c = std::clamp(c + uniform(-0.3, 0.3) * (lim.hi[i] - lim.lo[i]), lim.lo[i], lim.hi[i]);
      tr.centre[i] = c;
    }
    // The base motion: slow sines, amplitudes shrunk until the motion stays clear of the margin.
    double scale = 1.0;
    for (int i = 0; i < n; ++i)
      tr.waves[i] = {uniform(0.5, 1.0), 2 * M_PI * uniform(0.08, 0.3), uniform(0, 2 * M_PI),
                     uniform(0.2, 0.5), 2 * M_PI * uniform(0.25, 0.6), uniform(0, 2 * M_PI)};
    const std::vector<std::array<double, 6>> unit = tr.waves;
    bool clear = false;
    for (int shrink = 0; shrink < 6 && !clear; ++shrink, scale *= 0.6) {
      for (int i = 0; i < n; ++i) {
        // Room to the limits from the centre.
        const double room = std::max(0.0, std::min(tr.centre[i] - lim.lo[i], lim.hi[i] - tr.centre[i]));
        const double amp = std::min(lim.amplitude[i] * scale, 0.9 * room / 1.5);
        tr.waves[i] = unit[i];
        tr.waves[i][0] *= amp, tr.waves[i][3] *= amp;
      }
      const double d = minOver(tr, t0, t1);
      clear = d > 1.1 * margin + 0.002;
      if (debug) std::fprintf(stderr, "attempt %d scale %.3f base min distance %.4f\n", attempt, scale, d);
    }
    if (!clear) continue;

    // Events: towards a random colliding configuration; near ones stop at about half the margin.
    bool ok = true;
    for (Event e : plan) {
      bool found = false;
      for (int tries = 0; tries < 300 && !found; ++tries) {
        e.goal.assign(n, 0.0);
        // Within 1.05 rad (0.18 m) of the centre: joint speeds stay those of a robot at work.
        for (int i = 0; i < n; ++i) {
          const double reach = lim.amplitude[i] * 3.5;
          e.goal[i] = std::clamp(tr.centre[i] + uniform(-reach, reach), lim.lo[i], lim.hi[i]);
        }
        if (!(probe(e.goal) <= 0.0)) continue;
        if (e.kind == Event::Collision) {  // a goal well inside the collision: a contact of some duration
          std::vector<double> part(n);
          for (int i = 0; i < n; ++i) part[i] = tr.centre[i] + 0.8 * (e.goal[i] - tr.centre[i]);
          if (!(probe(part) <= 0.0)) continue;
        }
        Trajectory with = tr;
        int collision_frames = 0;
        const double from = e.time - e.half_width, to = e.time + e.half_width;
        if (e.kind == Event::Collision) {
          // The smallest blend that collides, then a little more: one short, clear contact.
          double lo = 0.0, hi = 1.0;
          for (int it = 0; it < 18; ++it) {
            e.beta = 0.5 * (lo + hi);
            with.events = tr.events;
            with.events.push_back(e);
            (minOver(with, from, to) <= 0.0 ? hi : lo) = e.beta;
          }
          // Then deeper until the contact lasts about 0.12 to 0.3 s.
          // Frames (at video times) must show it: at least two of them when the window allows.
          const double first = hi;
          for (const double f : {0.15, 0.3, 0.5, 0.75, 1.0}) {
            e.beta = std::min(1.0, first + f * (1.0 - first));
            with.events = tr.events;
            with.events.push_back(e);
            int touching = 0;
            for (int k = 0; k < samples; ++k) {
              const double t = t0 + k * dt;
              if (t < from || t > to) continue;
              with.at(t, q, qd);
              touching += probe(q) <= 0.0;
            }
            collision_frames = 0;
            for (int i = static_cast<int>(std::ceil(from * a.fps)); i / a.fps <= to; ++i) {
              with.at(i / a.fps, q, qd);
              collision_frames += probe(q) <= 0.0;
            }
            if (touching * dt >= std::min(0.12, 0.3 * e.half_width) && collision_frames >= 2) break;
          }
        } else {
          double lo = 0.0, hi = 1.0;
          for (int it = 0; it < 18; ++it) {
            e.beta = 0.5 * (lo + hi);
            with.events = tr.events;
            with.events.push_back(e);
            (minOver(with, from, to) <= near_target ? hi : lo) = e.beta;
          }
          e.beta = lo;
        }
        with.events = tr.events;
        with.events.push_back(e);
        e.min_distance = minOver(with, from, to);
        if (e.kind == Event::Collision)
          found = e.min_distance <= 0.0 && collision_frames >= 1;
        else
          found = e.min_distance > 0.3 * near_target && e.min_distance <= 1.6 * near_target && e.min_distance <= margin;
      }
      if (debug)
        std::fprintf(stderr, "event %d at %.2f: found %d beta %.3f min %.4f\n", int(e.kind), e.time, int(found), e.beta,
                     e.min_distance);
      if (!found) {
        ok = false;
        break;
      }
      tr.events.push_back(e);
    }
    if (ok) return tr;
  }
  throw UsageError(a.model + ": found no trajectory with near-collisions" +
                   std::string(a.no_collision ? "" : " and one collision") +
                   " within the joint limits (try another --seed or a longer --seconds)");
}

// ---------------------------------------------------------------------------------------------
// The scene: room, tags, light, camera.

struct Box3 {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  void add(const Vec3& p, double r) {
    lo = lo.cwiseMin(p - Vec3::Constant(r));
    hi = hi.cwiseMax(p + Vec3::Constant(r));
  }
};

// Where every body volume goes over the log samples.
Box3 robotBox(const Model& m, const StateLog& log) {
  Box3 box;
  std::vector<Pose> poses(m.joints.size());
  for (std::size_t k = 0; k < log.rows(); k += 4) {
    if (!framePoses(m, log.row(k), poses)) continue;
    for (const Body& b : m.bodies)
      for (const Vec3& p : b.points) box.add(framePose(poses, b.frame) * p, b.radius);
  }
  if (!(box.lo.x() <= box.hi.x())) box.add(Vec3::Zero(), 0.5);
  return box;
}

cv::Matx33d toCv(const Eigen::Matrix3d& r) {
  cv::Matx33d out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out(i, j) = r(i, j);
  return out;
}

calib::Camera defaultCamera(const Box3& box, int width, int height) {
  calib::Camera c;
  c.width = width, c.height = height;
  const double f = 0.8 * width;
  c.camera_matrix =
      cv::Matx33d(f, 0, 0.5 * width - 0.5 + 0.0031 * width, 0, f, 0.5 * height - 0.5 - 0.0029 * height, 0, 0, 1);
  c.distortion = {-0.12, 0.07, 0.0005, -0.0003, -0.015};
  const Vec3 target = 0.5 * (box.lo + box.hi);
  const double radius = std::max(0.4, 0.5 * (box.hi - box.lo).norm());
  const double half_fov = std::atan(0.5 * std::min(width, height) / f);
  const double distance = 0.72 * radius / std::sin(half_fov);
  const double az = 38.0 * M_PI / 180.0, el = 20.0 * M_PI / 180.0;
  const Vec3 eye = target + distance * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Vec3 z = (target - eye).normalized();
  const Vec3 x = z.cross(Vec3::UnitZ()).normalized();
  const Vec3 y = z.cross(x);
  Eigen::Matrix3d r_cw;
  r_cw.row(0) = x.transpose(), r_cw.row(1) = y.transpose(), r_cw.row(2) = z.transpose();
  cv::Rodrigues(toCv(r_cw), c.rvec);
  const Vec3 t = -r_cw * eye;
  c.tvec = cv::Vec3d(t.x(), t.y(), t.z());
  return c;
}

struct Room {
  double floor_z = 0, wall_x = 0, wall_y = 0;
  double sx = 1, sy = 1;  // the side of the walls the camera is on (+1: towards +x / +y)
  std::vector<calib::SceneSurface> surfaces;
  calib::SceneLight light;
};

Pose poseOf(const Eigen::Matrix3d& r, const Vec3& t) {
  Pose p = Pose::Identity();
  p.linear() = r;
  p.translation() = t;
  return p;
}

// Tag frame axes (columns x, y, z) on the floor and on the two walls (x as seen from the front).
const Eigen::Matrix3d& floorAxes() {
  static const Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  return r;
}
// The wall across x facing sx * x: seen from its front, right is sx * y.
Eigen::Matrix3d wallXAxes(double sx) {
  Eigen::Matrix3d r;
  r.col(0) = sx * Vec3::UnitY(), r.col(1) = Vec3::UnitZ(), r.col(2) = sx * Vec3::UnitX();
  return r;
}
// The wall across y facing sy * y: seen from its front, right is -sy * x.
Eigen::Matrix3d wallYAxes(double sy) {
  Eigen::Matrix3d r;
  r.col(0) = -sy * Vec3::UnitX(), r.col(1) = Vec3::UnitZ(), r.col(2) = sy * Vec3::UnitY();
  return r;
}

// A floor below the robot and two walls beyond it, on the far side from the camera at `eye`.
Room makeRoom(const Box3& box, const Vec3& eye) {
  Room room;
  const Vec3 c = 0.5 * (box.lo + box.hi);
  room.sx = eye.x() >= c.x() ? 1.0 : -1.0;
  room.sy = eye.y() >= c.y() ? 1.0 : -1.0;
  room.floor_z = box.lo.z() - 0.002;
  room.wall_x = room.sx > 0 ? box.lo.x() - 0.7 : box.hi.x() + 0.7;
  room.wall_y = room.sy > 0 ? box.lo.y() - 0.7 : box.hi.y() + 0.7;
  const double size = 12.0, height = 3.2;
  calib::SceneSurface floor;
  floor.pose = poseOf(floorAxes(), Vec3(c.x(), c.y(), room.floor_z));
  floor.half_x = floor.half_y = size;
  floor.colour = cv::Scalar(118, 128, 138);
  floor.tile_colour = cv::Scalar(104, 113, 124);
  floor.tile = 0.5;
  calib::SceneSurface wx;
  wx.pose = poseOf(wallXAxes(room.sx), Vec3(room.wall_x, c.y(), room.floor_z + 0.5 * height));
  wx.half_x = size, wx.half_y = 0.5 * height;
  wx.colour = cv::Scalar(196, 204, 210);
  calib::SceneSurface wy;
  wy.pose = poseOf(wallYAxes(room.sy), Vec3(c.x(), room.wall_y, room.floor_z + 0.5 * height));
  wy.half_x = size, wy.half_y = 0.5 * height;
  wy.colour = cv::Scalar(170, 186, 200);
  room.surfaces = {floor, wx, wy};
  room.light.on = true;
  room.light.position = Vec3(c.x() + room.sx * 0.6, c.y() + room.sy * 0.9, room.floor_z + height - 0.2);
  room.light.ambient = 0.5;
  room.light.diffuse = 0.65;
  room.light.reference = height - 0.2;
  return room;
}

// URDF rpy (R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation.
Vec3 rpyOf(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return {roll, pitch, yaw};
}

// Candidate tags on a grid over the floor and both walls, kept when the first frame shows them
// whole: inside the image, at least 24 px across, not covered by the robot's volumes.
calib::TagLayout makeTags(const Room& room, const Box3& box, const calib::Camera& cam, const cv::Mat& robot_mask,
                          std::vector<int>& visible) {
  const double span = std::max(box.hi.x() - box.lo.x(), box.hi.y() - box.lo.y());
  const double size = std::clamp(0.12 * span, 0.12, 0.3);
  struct Candidate {
    calib::Tag tag;
    int surface;
  };
  std::vector<Candidate> candidates;
  auto add = [&](const Eigen::Matrix3d& axes, const Vec3& at, int surface) {
    calib::Tag t;
    t.size = size;
    t.xyz = at;
    t.rpy = rpyOf(axes);
    candidates.push_back({t, surface});
  };
  const double sx = room.sx, sy = room.sy;
  const double reach = std::max(box.hi.x() - box.lo.x(), box.hi.y() - box.lo.y()) + 1.7;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 6; ++col) {
      const double h = room.floor_z + 0.35 + row * 0.55 + 0.1 * (col % 2);
      const double along = 0.3 + col * reach / 5.5;
      add(wallXAxes(sx), Vec3(room.wall_x + sx * 0.001, room.wall_y + sy * along, h), 1);
      add(wallYAxes(sy), Vec3(room.wall_x + sx * along, room.wall_y + sy * 0.001, h), 2);
    }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      const Vec3 at(room.wall_x + sx * (0.4 + i * reach / 5.0), room.wall_y + sy * (0.4 + j * reach / 5.0),
                    room.floor_z + 0.001);
      if (at.x() > box.lo.x() - size && at.x() < box.hi.x() + size && at.y() > box.lo.y() - size &&
          at.y() < box.hi.y() + size)
        continue;  // under the robot
      add(floorAxes(), at, 0);
    }
  cv::Mat covered;
  cv::dilate(robot_mask > 0, covered, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(15, 15)));
  const Pose w2c = cam.worldToCamera();
  const Vec3 eye = w2c.inverse().translation();
  std::vector<Candidate> kept;
  int per_surface[3] = {0, 0, 0};
  for (const Candidate& c : candidates) {
    if (per_surface[c.surface] >= 6) continue;
    // Seen from its front, at most 75 degrees off its normal.
    const Vec3 to_eye = (eye - c.tag.xyz).normalized();
    if (!(c.tag.pose().linear().col(2).dot(to_eye) > 0.26)) continue;
    const auto corners = c.tag.corners();
    // The whole bitmap (one white cell around the black square) must be in front and in view.
    std::vector<cv::Point3d> outer;
    bool in_front = true;
    for (const cv::Point3d& p : corners) {
      const Vec3 centre = c.tag.xyz;
      const Vec3 q = centre + 1.25 * (Vec3(p.x, p.y, p.z) - centre);
      outer.emplace_back(q.x(), q.y(), q.z());
      in_front = in_front && (w2c * q).z() > 0.2;
    }
    if (!in_front) continue;
    std::vector<cv::Point2d> px;
    cv::projectPoints(outer, cam.rvec, cam.tvec, cam.camera_matrix, cam.distortion, px);
    bool inside = true;
    double edge = 1e300;
    for (std::size_t k = 0; k < 4; ++k) {
      inside = inside && px[k].x > 8 && px[k].y > 8 && px[k].x < cam.width - 9 && px[k].y < cam.height - 9;
      edge = std::min(edge, cv::norm(px[k] - px[(k + 1) % 4]));
    }
    if (!inside || edge < 30.0) continue;
    std::vector<cv::Point> poly;
    for (const cv::Point2d& p : px)
      poly.emplace_back(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
    cv::Mat area = cv::Mat::zeros(covered.size(), CV_8U);
    cv::fillConvexPoly(area, poly, cv::Scalar(255));
    if (cv::countNonZero(area & covered) > 0) continue;
    kept.push_back(c);
    ++per_surface[c.surface];
  }
  calib::TagLayout layout;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    calib::Tag t = kept[i].tag;
    t.id = static_cast<int>(i);
    layout.tags.push_back(t);
    visible.push_back(t.id);
  }
  return layout;
}

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string tagLayoutText(const calib::TagLayout& layout) {
  std::ostringstream out;
  out << "# Tag layout of a kccd synth scene (tag36h11): size is the black square's edge (m); xyz, rpy the\n"
         "# tag frame in the world (URDF rpy). Floor tags face up, wall tags face into the room.\n"
         "tags:\n";
  for (const calib::Tag& t : layout.tags)
    out << "  - {id: " << t.id << ", size: " << g17(t.size) << ", xyz: [" << g17(t.xyz.x()) << ", " << g17(t.xyz.y())
        << ", " << g17(t.xyz.z()) << "], rpy: [" << g17(t.rpy.x()) << ", " << g17(t.rpy.y()) << ", " << g17(t.rpy.z())
        << "]}\n";
  return out.str();
}

std::string intrinsicsText(const calib::Camera& c) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "image_width" << c.width << "image_height" << c.height;
  fs << "camera_matrix" << cv::Mat(c.camera_matrix);
  fs << "distortion_coefficients" << cv::Mat(c.distortion).reshape(1, 1);
  return fs.releaseAndGetString();
}

// ---------------------------------------------------------------------------------------------
// Output folder: built under a temporary name beside DIR, renamed into place at the end.

std::string fourccCodec(const std::string& codec, int& fourcc) {
  if (codec == "ffv1") return fourcc = cv::VideoWriter::fourcc('F', 'F', 'V', '1'), "video.mkv";
  if (codec == "mjpg") return fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), "video.avi";
  if (codec == "mp4v") return fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v'), "video.mp4";
  throw UsageError("--codec: expected ffv1, mjpg or mp4v, got '" + codec + "'");
}

// Per-body colours of the visible geometry: static bodies dark grey, moving links alternating
// light and mid grey with blue accents.
cv::Scalar bodyColour(const Model& m, std::size_t i) {
  if (m.bodies[i].frame == kWorld) return {92, 96, 100};
  static const cv::Scalar palette[] = {{222, 222, 226}, {150, 152, 158}, {190, 120, 60}, {205, 208, 212}};
  return palette[i % 4];
}

// The frame pipeline's second stage (blur, noise, encoding) runs on its own thread while the next
// frame renders.
class Writer {
 public:
  Writer(cv::VideoWriter& video, std::string mask_dir, double blur, double noise, std::uint64_t seed)
      : video_(video), mask_dir_(std::move(mask_dir)), blur_(blur), noise_(noise), seed_(seed), thread_([this] {
          loop();
        }) {}
  ~Writer() { finish(); }
  void push(int index, cv::Mat frame, cv::Mat mask) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [&] { return queue_.size() < 2; });
    queue_.push_back({index, std::move(frame), std::move(mask)});
    ready_.notify_one();
  }
  /// Lens vignetting: a gain per pixel (CV_8UC3, 255 = 1) applied before blur and noise.
  void setVignette(cv::Mat gain) {
    const std::lock_guard<std::mutex> lock(mutex_);
    vignette_ = std::move(gain);
  }
  void finish() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
      ready_.notify_one();
    }
    if (thread_.joinable()) thread_.join();
  }
  int written() const { return written_; }
  /// Seconds spent in vignetting and blur, noise, video encoding, mask writing (after finish()).
  const std::array<double, 4>& stageSeconds() const { return stage_s_; }
  const std::string& error() const { return error_; }

 private:
  struct Item {
    int index;
    cv::Mat frame, mask;
  };
  void loop() {
    for (;;) {
      Item item;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [&] { return !queue_.empty() || done_; });
        if (queue_.empty()) return;
        item = std::move(queue_.front());
        queue_.pop_front();
        space_.notify_one();
      }
      if (!error_.empty()) continue;
      try {
        process(item);
      } catch (const std::exception& e) {  // OpenCV's encoders throw cv::Exception
        error_ = std::string("frame ") + std::to_string(item.index) + ": " + e.what();
      }
    }
  }
  // Vignetting, blur and noise, then the video frame and the mask file.
  void process(Item& item) {
    const auto t0 = Clock::now();
    cv::Mat f = item.frame;
    if (!vignette_.empty()) cv::multiply(f, vignette_, f, 1.0 / 255.0);
    if (blur_ > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), blur_, blur_, cv::BORDER_REFLECT);
    const auto t1 = Clock::now();
    if (noise_ > 0) {
      // Gaussian noise drawn once for a field 64 px larger than the frame; each frame takes it
      // at its own seeded offset (drawing 2.8 M normal numbers per frame cost 25 ms).
      constexpr int kPad = 64;
      if (noise_field_.empty()) {
        noise_field_.create(f.rows + kPad, f.cols + kPad, CV_16SC3);
        cv::RNG rng(seed_ * 1000003ull + 7);
        rng.fill(noise_field_, cv::RNG::NORMAL, 0.0, noise_);
      }
      cv::RNG rng(seed_ * 1000003ull + static_cast<std::uint64_t>(item.index) + 11);
      const int dx = rng.uniform(0, kPad), dy = rng.uniform(0, kPad);
      cv::Mat noisy;
      f.convertTo(noisy, CV_16SC3);
      if (rng.uniform(0, 2) == 0)
        noisy += noise_field_(cv::Rect(dx, dy, f.cols, f.rows));
      else
        noisy -= noise_field_(cv::Rect(dx, dy, f.cols, f.rows));
      noisy.convertTo(f, CV_8UC3);
    }
    const auto t2 = Clock::now();
    video_.write(f);
    const auto t3 = Clock::now();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%06d.png", item.index);
    std::vector<uchar> png;
    if (!cv::imencode(".png", item.mask, png, {cv::IMWRITE_PNG_COMPRESSION, 1})) {
      error_ = std::string("cannot encode mask ") + name;
      return;
    }
    // A new file in the temporary folder (the folder's rename publishes it).
    std::FILE* file = std::fopen((mask_dir_ + "/" + name).c_str(), "wb");
    const bool ok = file && std::fwrite(png.data(), 1, png.size(), file) == png.size();
    if (file && std::fclose(file) != 0) error_ = std::string("cannot write mask ") + name;
    if (!ok) error_ = std::string("cannot write mask ") + name;
    if (!error_.empty()) return;
    const auto t4 = Clock::now();
    stage_s_[0] += seconds(t0, t1), stage_s_[1] += seconds(t1, t2), stage_s_[2] += seconds(t2, t3),
        stage_s_[3] += seconds(t3, t4);
    ++written_;
  }
  cv::VideoWriter& video_;
  std::string mask_dir_;
  cv::Mat vignette_, noise_field_;
  std::array<double, 4> stage_s_{};
  double blur_, noise_;
  std::uint64_t seed_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<Item> queue_;
  bool done_ = false;
  int written_ = 0;
  std::string error_;
  std::thread thread_;
};

std::string stateLogText(const Model& m, const Trajectory& tr, double offset, double rate, double duration) {
  const int n = m.stateSize();
  std::string text = "time";
  for (const std::string& name : m.stateNames()) text += "," + name;
  for (const std::string& name : m.stateNames()) text += "," + name + ".vel";
  text += "\n";
  std::vector<double> q(n), qd(n);
  // Log time tau runs from 0 and covers every frame time plus the offset, a few samples beyond.
  const int rows = static_cast<int>(std::ceil((duration + offset) * rate)) + 3;
  char buf[64];
  for (int k = 0; k < rows; ++k) {
    const double tau = k / rate;
    tr.at(tau - offset, q, qd);
    std::snprintf(buf, sizeof buf, "%.6f", tau);
    text += buf;
    for (int i = 0; i < n; ++i) std::snprintf(buf, sizeof buf, ",%.9f", q[i]), text += buf;
    for (int i = 0; i < n; ++i) std::snprintf(buf, sizeof buf, ",%.9f", qd[i]), text += buf;
    text += "\n";
  }
  return text;
}

nlohmann::json vecJson(const cv::Vec3d& v) { return {v[0], v[1], v[2]}; }

Exit runSynth(const SynthArgs& a) {
  const auto t_start = Clock::now();
  const Model m = loadOrExplain(a.model);
  if (m.bodies.size() > 255) throw UsageError(a.model + ": more than 255 bodies do not fit an 8-bit mask");
  int fourcc = 0;
  const std::string video_name = fourccCodec(a.codec, fourcc);
  if (!(a.fps >= 1 && a.fps <= 240)) throw UsageError("--fps: must be 1 ... 240");
  if (std::floor(a.seconds * a.fps) < 1) throw UsageError("--seconds: too short for one frame at --fps");
  if (!(a.log_rate > 0) || std::abs(a.log_rate - a.fps) < 1e-9)
    throw UsageError("--log-rate: must differ from --fps (a real log runs on its own clock)");
  const fs::path out = fs::path(a.output).lexically_normal();
  if (out.empty() || out.filename().empty() || out.filename() == "." || out.filename() == "..")
    throw UsageError("-o " + a.output + ": give a folder name");
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec))
    throw UsageError("-o " + a.output + ": folder " + parent.string() + " does not exist");
  if (fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec)) && !a.force)
    throw UsageError("-o " + a.output + ": exists and is not an empty folder (use --force to replace it)");

  // The camera (given, or placed after the trajectory is known).
  std::optional<calib::Camera> given;
  if (!a.camera.empty()) {
    if (a.size_given)
      throw UsageError("--width/--height shape the default camera; the camera file " + a.camera + " fixes the size");
    given = calib::loadCamera(a.camera);
  } else if (a.width < 64 || a.height < 64 || a.width > 4096 || a.height > 4096) {
    throw UsageError("--width/--height: must be 64 ... 4096 pixels");
  }

  Progress progress("synth", a.quiet);
  const int frames = static_cast<int>(std::floor(a.seconds * a.fps + 1e-9));
  const double duration = (frames - 1) / a.fps;
  const double dt = 1.0 / a.log_rate;
  // The search works on the analytic motion; the frames show the logged one. A trajectory whose
  // frames do not have exactly the wanted collision intervals is searched again (another stream).
  const double max_gap = 1.5 * dt;
  Trajectory trajectory;
  std::string log_text;
  StateLog log;
  std::vector<std::vector<double>> states(frames, std::vector<double>(m.stateSize()));
  std::vector<double> min_distance(frames);
  std::vector<int> closest(frames, -1);
  std::vector<std::array<int, 2>> intervals;
  DistanceProbe probe(m);
  for (int round = 0;; ++round) {
    SynthArgs ar = a;
    ar.seed = a.seed + 0x51ED270B27ull * static_cast<std::uint64_t>(round);
    trajectory = searchTrajectory(m, ar, -a.time_offset, duration + 0.1, dt);
    log_text = stateLogText(m, trajectory, a.time_offset, a.log_rate, duration);
    log = parseStateLog(log_text, "states.csv", m);
    // Per frame: the logged state at the frame's log time, its distances.
    for (int i = 0; i < frames; ++i) {
      const double t = i / a.fps;
      if (stateAt(log, t + a.time_offset, max_gap, states[i]) == StateMatch::None)
        throw std::logic_error("synth: the log misses frame " + std::to_string(i));
      min_distance[i] = probe(states[i], &closest[i]);
    }
    intervals.clear();
    for (int i = 0; i < frames; ++i)
      if (min_distance[i] <= 0.0) {
        if (!intervals.empty() && intervals.back()[1] == i - 1)
          intervals.back()[1] = i;
        else
          intervals.push_back({i, i});
      }
    if (intervals.size() == (a.no_collision ? 0u : 1u)) break;
    if (round == 7)
      throw UsageError(a.model + ": the trajectories found have " + std::to_string(intervals.size()) +
                       " collision intervals at this frame rate (try another --seed, --fps or --seconds)");
  }
  const auto t_traj = Clock::now();
  const Box3 box = robotBox(m, log);
  const calib::Camera camera = given ? *given : defaultCamera(box, a.width, a.height);
  const Room room = makeRoom(box, camera.worldToCamera().inverse().translation());

  // Renderer: the visible geometry, shaded, with its label mask.
  render::RenderOptions ro;
  ro.supersample = 2.0;
  ro.mask_supersample = 2.0;
  std::unique_ptr<render::Renderer> renderer;
  try {
    renderer = std::make_unique<render::Renderer>(camera, ro);
  } catch (const calib::CameraError& e) {
    std::string msg = e.what();
    if (msg.rfind("camera: ", 0) == 0) msg = msg.substr(8);
    throw UsageError((a.camera.empty() ? std::string("camera") : a.camera) + ": " + msg);
  }
  Checker checker(m);
  auto volumesAt = [&](std::span<const double> q, double scale) {
    checker.query(q, q, QueryOptions{.type = QueryType::Distances});
    std::vector<render::Volume> v = render::staticSceneVolumes(m, checker, q, {});
    for (std::size_t b = 0; b < v.size(); ++b) {
      v[b].radius *= scale;
      v[b].colour = bodyColour(m, b);
    }
    return v;
  };
  // The robot's appearance: its visual meshes (the model's visuals:) or shrunken SSCHs.
  const bool use_visuals = a.appearance == "visuals" || (a.appearance == "auto" && !m.visuals.empty());
  if (use_visuals && m.visuals.empty()) throw UsageError("--appearance visuals: " + a.model + " has no visuals:");
  if (use_visuals && m.visuals.size() > 255)
    throw UsageError(a.model + ": " + std::to_string(m.visuals.size()) + " visuals: at most 255 can be drawn");
  if (use_visuals && a.shrink_given) throw UsageError("--visible-scale: applies to --appearance volumes only");
  const std::vector<render::LoadedVisual> visuals = use_visuals ? render::loadVisuals(m) : std::vector<render::LoadedVisual>{};
  auto visibleAt = [&](std::span<const double> q) {
    return use_visuals ? render::visualVolumes(m, visuals, q) : volumesAt(q, a.shrink);
  };
  render::Style style;
  style.shaded = true;
  style.legend = false;

  // Tags: visible in the first frame around the robot's full volumes.
  std::vector<int> visible_tags;
  calib::TagLayout layout;
  {
    const std::vector<render::Volume> full = volumesAt(states[0], 1.0);
    const render::Frame f0 = renderer->render(full, style, false, true);
    layout = makeTags(room, box, camera, f0.mask, visible_tags);
  }
  if (layout.tags.size() < 4)
    throw UsageError("camera: it sees fewer than 4 whole tags of the synthetic room (" +
                     std::to_string(layout.tags.size()) + "); point it at the robot from farther away");

  // The static background: floor, walls, tags, light.
  calib::TagSceneOptions so;
  so.supersample = 3;
  so.white = 235, so.black = 30, so.background = 90;
  so.surfaces = room.surfaces;
  so.light = room.light;
  so.seed = a.seed;
  const cv::Mat background = calib::renderTagSceneBgr(camera, layout, so);
  const auto t_bg = Clock::now();

  // Output folder, staged: an existing one is replaced only when the new one is complete.
  overlay::StagedOutput staged(out, overlay::StagedOutput::Kind::Folder, "-o " + a.output,
                               overlay::StagedOutput::Existing::ReplaceFolder);
  const std::string dir = staged.path().string();
  const std::string mask_dir = dir + "/masks";
  fs::create_directory(mask_dir);
  cv::VideoWriter video;
  video.open(dir + "/" + video_name, cv::CAP_FFMPEG, fourcc, a.fps, cv::Size(camera.width, camera.height), true);
  if (!video.isOpened()) throw UsageError("--codec " + a.codec + ": OpenCV cannot write this video here");

  double render_s = 0.0;
  int written = 0;
  std::array<double, 4> writer_s{};
  {
    Writer writer(video, mask_dir, a.blur, a.noise, a.seed);
    {
      // Natural vignetting: 1 - 0.25 r^2, r the distance from the principal point over the half diagonal.
      cv::Mat gain(camera.height, camera.width, CV_8UC3);
      const double cx = camera.camera_matrix(0, 2), cy = camera.camera_matrix(1, 2);
      const double half_diagonal2 = 0.25 * (static_cast<double>(camera.width) * camera.width +
                                            static_cast<double>(camera.height) * camera.height);
      for (int v = 0; v < camera.height; ++v)
        for (int u = 0; u < camera.width; ++u) {
          const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / half_diagonal2;
          gain.at<cv::Vec3b>(v, u) = cv::Vec3b::all(cv::saturate_cast<uchar>(255.0 * (1.0 - 0.25 * std::min(r2, 2.0))));
        }
      writer.setVignette(gain);
    }
    for (int i = 0; i < frames; ++i) {
      const auto r0 = Clock::now();
      const std::vector<render::Volume> visible = visibleAt(states[i]);
      const render::Frame f = renderer->render(visible, style, true, true);
      cv::Mat frame = background.clone();
      render::compositeOver(frame, f.bgra);
      render_s += seconds(r0, Clock::now());
      writer.push(i, std::move(frame), f.mask);
      progress.update(static_cast<double>(i + 1) / frames);
    }
    writer.finish();
    if (!writer.error().empty()) throw UsageError("-o " + a.output + ": " + writer.error());
    written = writer.written();
    writer_s = writer.stageSeconds();
  }
  video.release();
  progress.finish();
  if (written != frames)
    throw std::runtime_error("synth: wrote " + std::to_string(written) + " of " + std::to_string(frames) + " frames");

  // Text outputs.
  writeFileAtomically(dir + "/states.csv", log_text);
  writeFileAtomically(dir + "/camera_true.yaml", calib::cameraText(camera));
  writeFileAtomically(dir + "/intrinsics.yaml", intrinsicsText(camera));
  writeFileAtomically(dir + "/tags.yaml", tagLayoutText(layout));

  const auto t_end = Clock::now();
  nlohmann::json j;
  j["kccd_synth"] = 1;
  j["model"] = a.model;
  j["model_name"] = m.name;
  j["seed"] = a.seed;
  j["margin"] = m.safety_margin;
  j["video"] = {{"file", video_name},
                {"codec", a.codec},
                {"fps", a.fps},
                {"frames", frames},
                {"width", camera.width},
                {"height", camera.height},
                {"frame_time", "frame i is at video time i / fps"},
                {"blur_sigma_px", a.blur},
                {"noise_sigma", a.noise}};
  j["state_log"] = {{"file", "states.csv"},         {"rate_hz", a.log_rate},
                    {"rows", log.rows()},           {"velocity_columns", true},
                    {"time_offset", a.time_offset}, {"clock", "log time = video time + time_offset"}};
  const Pose c2w = camera.worldToCamera().inverse();
  j["camera"] = {{"file", "camera_true.yaml"},   {"intrinsics_file", "intrinsics.yaml"},
                 {"given", !a.camera.empty()},   {"rvec", vecJson(camera.rvec)},
                 {"tvec", vecJson(camera.tvec)}, {"position", vec3(c2w.translation())}};
  j["tags"] = {{"file", "tags.yaml"}, {"count", layout.tags.size()}, {"visible_in_first_frame", visible_tags}};
  j["masks"] = {{"folder", "masks"},
                {"pattern", "frame_%06d.png"},
                {"labels", "0 background, i + 1 where body i's visible geometry is nearest (model order)"},
                {"appearance", use_visuals ? "visuals" : "volumes"},
                {"visible_radius_scale", a.shrink}};
  j["render"] = {{"supersample", ro.supersample}, {"mask_supersample", ro.mask_supersample}};
  j["room"] = {{"floor_z", room.floor_z}, {"wall_x", room.wall_x}, {"wall_y", room.wall_y}};
  nlohmann::json coll = nlohmann::json::array(), near = nlohmann::json::array(), frames_json = nlohmann::json::array();
  for (int i = 0; i < frames; ++i) {
    const double d = min_distance[i];
    const char* status = d <= 0.0 ? "colliding" : d <= m.safety_margin ? "within_margin" : "clear";
    if (d <= 0.0)
      coll.push_back(i);
    else if (d <= m.safety_margin)
      near.push_back(i);
    nlohmann::json fj = {
        {"index", i},       {"time", i / a.fps}, {"log_time", i / a.fps + a.time_offset}, {"min_distance", number(d)},
        {"status", status}, {"state", states[i]}};
    if (closest[i] >= 0)
      fj["closest_pair"] = {m.bodies[m.pairs[closest[i]].a].name, m.bodies[m.pairs[closest[i]].b].name};
    frames_json.push_back(fj);
  }
  nlohmann::json iv = nlohmann::json::array();
  for (const auto& [first, last] : intervals)
    iv.push_back({{"first", first}, {"last", last}, {"time", {first / a.fps, last / a.fps}}});
  j["collision"] = {{"frames", coll}, {"intervals", iv}};
  j["near_collision_frames"] = near;
  nlohmann::json ev = nlohmann::json::array();
  for (const Event& e : trajectory.events)
    ev.push_back({{"kind", e.kind == Event::Collision ? "collision" : "near"},
                  {"time", e.time},
                  {"half_width", e.half_width},
                  {"plateau", e.plateau},
                  {"blend", e.beta},
                  {"min_distance", number(e.min_distance)}});
  j["events"] = ev;
  j["frames"] = frames_json;
  j["timing"] = {{"total_s", seconds(t_start, t_end)},
                 {"trajectory_s", seconds(t_start, t_traj)},
                 {"background_s", seconds(t_traj, t_bg)},
                 {"render_ms_per_frame", 1e3 * render_s / frames},
                 {"writer_ms_per_frame",
                  {{"vignette_blur", 1e3 * writer_s[0] / frames},
                   {"noise", 1e3 * writer_s[1] / frames},
                   {"encode_video", 1e3 * writer_s[2] / frames},
                   {"masks", 1e3 * writer_s[3] / frames}}},
                 {"renderer", renderer->rendererString()}};
  writeFileAtomically(dir + "/synth.json", j.dump(1) + "\n");

  staged.commit();  // into place
  if (!a.quiet) {
    std::cout << "wrote " << a.output << ": " << frames << " frames " << camera.width << "x" << camera.height << " at "
              << a.fps << " fps (" << video_name << "), states.csv at " << a.log_rate << " Hz (log time = video time + "
              << a.time_offset << " s), " << layout.tags.size() << " tags, in " << format(seconds(t_start, t_end), 3)
              << " s\n";
    if (!intervals.empty())
      std::cout << "collision: frames " << intervals[0][0] << "-" << intervals[0][1] << "; " << near.size()
                << " frames within the margin\n";
    else
      std::cout << "no collision; " << near.size() << " frames within the margin\n";
  }
  return Exit::Ok;
}

}  // namespace

Runner addSynth(CLI::App& app) {
  auto a = std::make_shared<SynthArgs>();
  CLI::App* sub = app.add_subcommand(
      "synth", "Synthetic recording with ground truth: video, state log, true camera, tags, masks, summary");
  sub->add_option("model", a->model, "Model file (YAML, kccd: 1)")->required();
  sub->add_option("-o,--output", a->output, "Output folder (created; complete only when the command succeeds)")
      ->required();
  sub->add_option("--camera", a->camera,
                  "Camera file to film with (default: one placed to see the robot, the floor and two walls)");
  sub->add_option("--seconds", a->seconds, "Length of the recording (s)")
      ->capture_default_str()
      ->check(finiteIn(0.04, 600));
  sub->add_option("--fps", a->fps, "Video frame rate")->capture_default_str()->check(finiteIn(1, 240));
  CLI::Option* width = sub->add_option("--width", a->width, "Image width of the default camera (px)")
                           ->capture_default_str()
                           ->check(CLI::Range(64, 4096));
  CLI::Option* height = sub->add_option("--height", a->height, "Image height of the default camera (px)")
                            ->capture_default_str()
                            ->check(CLI::Range(64, 4096));
  sub->add_option("--seed", a->seed, "Seed of the trajectory search and the noise")->capture_default_str();
  sub->add_option("--codec", a->codec, "ffv1 (video.mkv, lossless), mjpg (video.avi) or mp4v (video.mp4)")
      ->capture_default_str();
  sub->add_option("--log-rate", a->log_rate, "State log rate (Hz; must differ from --fps)")
      ->capture_default_str()
      ->check(finiteIn(1, 10000));
  sub->add_option("--time-offset", a->time_offset, "Log clock minus video clock (s; the log starts at log time 0)")
      ->capture_default_str()
      ->check(finiteIn(0, 10));
  CLI::Option* shrink = sub->add_option("--visible-scale", a->shrink,
                                         "Radius of the visible geometry as a fraction of the SSCH radius (--appearance volumes)")
      ->capture_default_str()
      ->check(finiteIn(0.1, 0.95));
  sub->add_option("--appearance", a->appearance,
                  "What the robot looks like: visuals (the model's visual meshes), volumes (its SSCHs shrunk by "
                  "--visible-scale), auto (visuals when the model has them)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "volumes", "visuals"}));
  sub->add_option("--blur", a->blur, "Gaussian blur of every frame (sigma, px)")
      ->capture_default_str()
      ->check(finiteIn(0, 10));
  sub->add_option("--noise", a->noise, "Gaussian sensor noise (sigma, grey levels)")
      ->capture_default_str()
      ->check(finiteIn(0, 50));
  sub->add_flag("--no-collision", a->no_collision, "Only near-collisions, no real one");
  sub->add_flag("--force", a->force, "Replace an existing output folder");
  sub->add_flag("-q,--quiet", a->quiet, "No progress and no summary line");
  sub->footer(
      "Writes DIR/video.mkv (or .avi, .mp4), DIR/states.csv (time, every state value and its .vel),\n"
      "DIR/camera_true.yaml, DIR/intrinsics.yaml (no pose), DIR/tags.yaml, DIR/masks/frame_%06d.png (label\n"
      "mask of the visible geometry: 0 background, i + 1 body i; a visual counts for the first body in its\n"
      "frame, 0 when there is none) and DIR/synth.json (the truth: camera,\n"
      "clock offset, rates, per-frame state and smallest distance, collision frames).\n"
      "Collision means a smallest distance bound <= 0 at the logged state of the frame.\n"
      "Exit status: 0 written, 2 bad input (or no trajectory found for this model and seed).");
  return [a, width, height, shrink] {
    a->size_given = width->count() > 0 || height->count() > 0;
    a->shrink_given = shrink->count() > 0;
    return runSynth(*a);
  };
}

}  // namespace kccd::cli
