// The scene of a synthetic recording: the box the robot moves in, the default camera, a room (a
// tiled floor and two walls, lit by a point light) and the AprilTags on it, and the room drawn once
// as the static background by the tag scene renderer (kccd/calib/tag_scene.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/calib/tag_scene.hpp"
#include "kccd/model.hpp"
#include "kccd/ssch.hpp"
#include "kccd/state_log.hpp"

namespace kccd::overlay {

using calib::SceneLight;  // the room drawn by calibration's tag scene renderer
using calib::SceneSurface;

/// An axis-aligned box (empty until something is added).
struct Box3 {
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  /// Grows the box to hold the ball of radius r at p.
  void add(const Vec3& p, double r) {
    lo = lo.cwiseMin(p - Vec3::Constant(r));
    hi = hi.cwiseMax(p + Vec3::Constant(r));
  }
};

/// Where every body volume goes over the log (every 4th row); a 0.5 m ball at the origin when no
/// row is a valid configuration.
Box3 robotBox(const Model& m, const StateLog& log);

/// The default camera: width x height, f = 0.8 width, mild barrel distortion, 38 degrees to the
/// side of and 20 degrees above the box, far enough to see all of it.
calib::Camera defaultCamera(const Box3& box, int width, int height);

/// A floor below the robot and two walls beyond it, on the far side from the camera.
struct Room {
  double floor_z = 0, wall_x = 0, wall_y = 0;
  double sx = 1, sy = 1;               ///< the side of the walls the camera is on (+1: towards +x / +y)
  std::vector<SceneSurface> surfaces;  ///< floor, the wall across x, the wall across y
  SceneLight light;
};

/// The room around `box` seen from `eye` (the camera's position).
Room makeRoom(const Box3& box, const Vec3& eye);

/// The scene of one recording.
struct SynthScene {
  Box3 box;                       ///< robotBox of the log
  calib::Camera camera;           ///< the camera filmed with (given or defaultCamera)
  Room room;                      ///< makeRoom around the box, seen from the camera
  calib::TagLayout layout;        ///< makeTags
  std::vector<int> visible_tags;  ///< ids of the tags the first frame shows whole
};

/// Candidate tags on a grid over the floor and both walls, kept when the first frame shows them
/// whole: from their front, inside the image, at least 30 px across, not covered by the robot
/// (`robot_mask`, nonzero where the robot's full volumes are, dilated by 7 px); at most 6 per
/// surface, numbered from 0 in that order. `visible` gets the ids of the tags kept.
calib::TagLayout makeTags(const Room& room, const Box3& box, const calib::Camera& cam, const cv::Mat& robot_mask,
                          std::vector<int>& visible);

/// The static background: the room with its tags through the camera's full lens model (BGR,
/// supersampled 3 x 3 at edges; `seed` for the renderer's randomness).
cv::Mat renderRoom(const calib::Camera& camera, const calib::TagLayout& layout, const Room& room, std::uint64_t seed);

}  // namespace kccd::overlay
