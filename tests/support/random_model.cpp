#include "random_model.hpp"

#include <cmath>

#include "random_shapes.hpp"
#include "reference_distance.hpp"

namespace kccd::testing {
namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}
int uniformInt(std::mt19937_64& rng, int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }

Eigen::Matrix3d axisAngle(const Vec3& w) {
  const double a = w.norm();
  if (a == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

}  // namespace

Model randomModel(std::mt19937_64& rng, int max_joints, int max_bodies, MobileBase base) {
  Model m;
  m.name = "random";
  const int budgets[] = {4, 8, 32};
  m.point_budget = budgets[uniformInt(rng, 0, 2)];
  if (base != MobileBase::None) {
    Pose origin = Pose::Identity();
    origin.linear() = randomRotation(rng);
    origin.translation() = Vec3(uniform(rng, -0.4, 0.4), uniform(rng, -0.4, 0.4), uniform(rng, -0.4, 0.4));
    const Vec3 n = randomUnit(rng);
    const Vec3 u = n.unitOrthogonal(), v = n.cross(u);
    auto add = [&](const char* name, JointType type, const Vec3& axis) {
      Joint j;
      j.name = name;
      j.parent = m.joints.empty() ? kWorld : static_cast<int>(m.joints.size()) - 1;
      j.type = type;
      j.origin = m.joints.empty() ? origin : Pose::Identity();
      j.axis = axis;
      j.sweep = uniformInt(rng, 0, 4) == 0 ? SweepMode::Exact : SweepMode::Accurate;
      if (type == JointType::Translation3d) j.error = uniform(rng, 0.0, 1.0) < 0.3 ? 0.0 : uniform(rng, 0.0, 0.05);
      if (type == JointType::Rotation3d) j.error = uniform(rng, 0.0, 1.0) < 0.3 ? 0.0 : uniform(rng, 0.0, 0.4);
      m.joints.push_back(j);
    };
    if (base == MobileBase::Planar) {
      add("base_x", JointType::Prismatic, u);
      add("base_y", JointType::Prismatic, v);
      add("base_yaw", JointType::Revolute, n);
    } else {
      add("base", JointType::Translation3d, Vec3::UnitZ());
      add("base_rotation", JointType::Rotation3d, Vec3::UnitZ());
    }
  }
  const int first = static_cast<int>(m.joints.size());
  const int nj = first + uniformInt(rng, 1, max_joints);
  for (int i = first; i < nj; ++i) {
    Joint j;
    j.name = std::to_string(i);
    j.name.insert(0, 1, 'j');
    j.parent = uniformInt(rng, -1, i - 1);
    const int t = uniformInt(rng, 0, 9);
    j.type = t < 5   ? JointType::Revolute
             : t < 7 ? JointType::Prismatic
             : t < 8 ? JointType::Fixed
             : t < 9 ? JointType::Translation3d
                     : JointType::Rotation3d;
    j.origin = Pose::Identity();
    j.origin.linear() = randomRotation(rng);
    j.origin.translation() = Vec3(uniform(rng, -0.4, 0.4), uniform(rng, -0.4, 0.4), uniform(rng, -0.4, 0.4));
    j.axis = randomUnit(rng);
    j.sweep = uniformInt(rng, 0, 4) == 0 ? SweepMode::Exact : SweepMode::Accurate;
    if (j.type == JointType::Translation3d) j.error = uniform(rng, 0.0, 1.0) < 0.3 ? 0.0 : uniform(rng, 0.0, 0.05);
    if (j.type == JointType::Rotation3d) j.error = uniform(rng, 0.0, 1.0) < 0.3 ? 0.0 : uniform(rng, 0.0, 0.4);
    m.joints.push_back(j);
  }
  const int nb = uniformInt(rng, 2, max_bodies);
  for (int i = 0; i < nb; ++i) {
    Body b;
    b.name = std::to_string(i);
    b.name.insert(0, 1, 'b');
    b.frame = uniformInt(rng, -1, nj - 1);
    const Vec3 centre(uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6));
    // Mostly a few points; one body in four as many as an imported link's (support cells).
    const int n_points = uniformInt(rng, 0, 3) == 0 ? uniformInt(rng, 12, 48) : uniformInt(rng, 1, 6);
    b.points = randomCloud(rng, n_points, centre, uniform(rng, 0.01, 0.3));
    b.radius = uniform(rng, 0.0, 1.0) < 0.2 ? 0.0 : uniform(rng, 0.0, 0.05);
    m.bodies.push_back(b);
  }
  m.finalize(true, {}, {});
  return m;
}

void randomBox(std::mt19937_64& rng, const Model& m, std::vector<double>& lower, std::vector<double>& upper) {
  const double widths[] = {0.0, 1e-12, 1e-6, 0.02, 0.1, 0.35, 1.0, 2.0, 3.3, 5.0, 6.3, 7.0};
  lower.assign(m.stateSize(), 0.0);
  upper.assign(m.stateSize(), 0.0);
  for (const Joint& j : m.joints) {
    const double scale = (j.type == JointType::Prismatic || j.type == JointType::Translation3d) ? 0.1 : 1.0;
    for (int k = 0; k < j.dof; ++k) {
      const int s = j.state_offset + k;
      const double centre = uniform(rng, -3.5, 3.5) * scale;
      double width = widths[uniformInt(rng, 0, 11)] * scale;
      if (j.type == JointType::Rotation3d) width = std::min(width, 0.6);
      if (j.sweep == SweepMode::Exact) width = 0.0;
      lower[s] = centre - 0.5 * width;
      upper[s] = lower[s] + width;
    }
  }
}

Sample sampleBox(std::mt19937_64& rng, const Model& m, const std::vector<double>& lower,
                 const std::vector<double>& upper, int kind) {
  Sample s;
  s.q.resize(lower.size());
  const int edge_axis = uniformInt(rng, 0, std::max(0, static_cast<int>(lower.size()) - 1));
  for (std::size_t i = 0; i < lower.size(); ++i) {
    const bool corner = kind == 0 || (kind == 1 && static_cast<int>(i) != edge_axis);
    if (corner) {
      s.q[i] = uniform(rng, 0.0, 1.0) < 0.5 ? lower[i] : upper[i];
    } else {
      s.q[i] = lower[i] + uniform(rng, 0.0, 1.0) * (upper[i] - lower[i]);
    }
  }
  for (const Joint& j : m.joints) {
    // Errors at their bound (the worst case) most of the time, inside it otherwise.
    const double fraction = uniform(rng, 0.0, 1.0) < 0.7 ? 1.0 : uniform(rng, 0.0, 1.0);
    s.translation_error.push_back(j.type == JointType::Translation3d ? Vec3(randomUnit(rng) * j.error * fraction)
                                                                     : Vec3::Zero());
    s.rotation_error.push_back(j.type == JointType::Rotation3d ? axisAngle(randomUnit(rng) * j.error * fraction)
                                                               : Eigen::Matrix3d::Identity());
    s.error_first.push_back(uniform(rng, 0.0, 1.0) < 0.5);
  }
  return s;
}

std::vector<Pose> jointPoses(const Model& m, const Sample& s) {
  std::vector<Pose> world(m.joints.size(), Pose::Identity());
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    const Joint& j = m.joints[i];
    const double* q = s.q.data() + j.state_offset;
    Pose motion = Pose::Identity();
    switch (j.type) {
      case JointType::Fixed:
        break;
      case JointType::Revolute:
        motion.linear() = Eigen::AngleAxisd(q[0], j.axis).toRotationMatrix();
        break;
      case JointType::Prismatic:
        motion.translation() = q[0] * j.axis;
        break;
      case JointType::Translation3d:
        motion.translation() = Vec3(q[0], q[1], q[2]) + s.translation_error[i];
        break;
      case JointType::Rotation3d: {
        const Eigen::Matrix3d measured = axisAngle(Vec3(q[0], q[1], q[2]));
        motion.linear() = s.error_first[i] ? Eigen::Matrix3d(measured * s.rotation_error[i])
                                           : Eigen::Matrix3d(s.rotation_error[i] * measured);
        break;
      }
    }
    const Pose parent = j.parent == kWorld ? Pose::Identity() : world[j.parent];
    world[i] = parent * j.origin * motion;
  }
  return world;
}

std::vector<Eigen::Vector3d> worldPoints(const Model& m, const std::vector<Pose>& poses, int body) {
  const Body& b = m.bodies[body];
  const Pose frame = b.frame == kWorld ? Pose::Identity() : poses[b.frame];
  std::vector<Eigen::Vector3d> out;
  for (const Vec3& p : b.points) out.push_back(frame * p);
  return out;
}

double referencePairDistance(const Model& m, const std::vector<Pose>& poses, const BodyPair& pair) {
  return static_cast<double>(referenceSschDistance(worldPoints(m, poses, pair.a), m.bodies[pair.a].radius,
                                                   worldPoints(m, poses, pair.b), m.bodies[pair.b].radius));
}

}  // namespace kccd::testing
