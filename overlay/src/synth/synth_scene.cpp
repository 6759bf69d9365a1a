// The scene of a synthetic recording (kccd/overlay/synth/synth_scene.hpp): the robot's box, the default
// camera, the room and its tags, the static background.
#include "kccd/overlay/synth/synth_scene.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/kinematics.hpp"

namespace kccd::overlay {
namespace {

cv::Matx33d toCv(const Eigen::Matrix3d& r) {
  cv::Matx33d out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out(i, j) = r(i, j);
  return out;
}

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

// URDF rpy (R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation.
Vec3 rpyOf(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return {roll, pitch, yaw};
}

}  // namespace

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

Room makeRoom(const Box3& box, const Vec3& eye) {
  Room room;
  const Vec3 c = 0.5 * (box.lo + box.hi);
  room.sx = eye.x() >= c.x() ? 1.0 : -1.0;
  room.sy = eye.y() >= c.y() ? 1.0 : -1.0;
  room.floor_z = box.lo.z() - 0.002;
  room.wall_x = room.sx > 0 ? box.lo.x() - 0.7 : box.hi.x() + 0.7;
  room.wall_y = room.sy > 0 ? box.lo.y() - 0.7 : box.hi.y() + 0.7;
  const double size = 12.0, height = 3.2;
  SceneSurface floor;
  floor.pose = poseOf(floorAxes(), Vec3(c.x(), c.y(), room.floor_z));
  floor.half_x = floor.half_y = size;
  floor.colour = cv::Scalar(118, 128, 138);
  floor.tile_colour = cv::Scalar(104, 113, 124);
  floor.tile = 0.5;
  SceneSurface wx;
  wx.pose = poseOf(wallXAxes(room.sx), Vec3(room.wall_x, c.y(), room.floor_z + 0.5 * height));
  wx.half_x = size, wx.half_y = 0.5 * height;
  wx.colour = cv::Scalar(196, 204, 210);
  SceneSurface wy;
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

cv::Mat renderRoom(const calib::Camera& camera, const calib::TagLayout& layout, const Room& room, std::uint64_t seed) {
  calib::TagSceneOptions so;
  so.supersample = 3;
  so.white = 235, so.black = 30, so.background = 90;
  so.surfaces = room.surfaces;
  so.light = room.light;
  so.seed = seed;
  return calib::renderTagSceneBgr(camera, layout, so);
}

}  // namespace kccd::overlay
