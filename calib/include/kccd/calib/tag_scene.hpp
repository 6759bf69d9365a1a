// Synthetic AprilTag frames: what a calibrated camera sees of a tag layout (and optionally of the
// floor and walls the tags are fixed to), drawn by ray casting through the camera's full lens
// model. The static background of `kccd synth` (the room and its tags, overlay/src/synth/) and the
// oracle of calibration's image tests and benchmark (it uses neither the detector nor the solver,
// only the camera model and the tag36h11 bitmaps). No calibration routine calls it; it is part of
// kccd_calib, beside the tag layout it draws, so that those tests build with calibration alone.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/ssch.hpp"

namespace kccd::calib {

/// A flat rectangle behind the tags (a floor, a wall), drawn from whichever side the camera is on.
/// Tags fixed to it must lie slightly in front of it (nearest hit wins).
struct SceneSurface {
  Pose pose = Pose::Identity();           ///< surface frame -> world; the rectangle is in its x-y plane
  double half_x = 1.0, half_y = 1.0;      ///< half extents along the surface's x and y, metres
  cv::Scalar colour{200, 200, 200};       ///< BGR, 0..255
  double tile = 0.0;                      ///< checker tiles of this edge (metres); 0: plain
  cv::Scalar tile_colour{180, 180, 180};  ///< the other tiles' colour
};

/// A point light: every surface and tag hit is scaled by ambient + diffuse * cos(incidence) *
/// (reference / distance)^2 (Lambert with inverse-square fall-off).
struct SceneLight {
  bool on = false;
  Vec3 position = Vec3::Zero();  ///< world, metres
  double ambient = 1.0, diffuse = 0.0;
  double reference = 1.0;  ///< distance at which the diffuse term is `diffuse` at normal incidence
};

/// How a tag scene is drawn. Grey levels are 0..255; the image is rounded and clipped to 8 bits
/// after blur and noise.
struct TagSceneOptions {
  int supersample = 4;                 ///< s: s x s sub-pixel rays (n-rooks pattern) in pixels at cell edges (1..16)
  double white = 230.0;                ///< the tags' white cells
  double black = 25.0;                 ///< the tags' black cells
  double background = 200.0;           ///< grey behind the tags (where no tag is hit)
  bool texture = false;                ///< a smooth random grey texture plus clutter (shapes, lines) behind the tags
  double blur_sigma = 0.0;             ///< Gaussian blur of the whole image, pixels (0: none)
  double noise_sigma = 0.0;            ///< additive Gaussian noise, grey levels (0: none)
  std::uint64_t seed = 1;              ///< texture, clutter and noise
  std::vector<SceneSurface> surfaces;  ///< floor and walls (none: only the background grey)
  SceneLight light;                    ///< lighting of tags and surfaces (off: unlit)
};

/// The 8-bit grey image (camera.width x camera.height, CV_8UC1) `camera` sees of `layout`: every
/// tag its tag36h11 bitmap (apriltag_to_image: 10 x 10 cells, a white border cell around the black
/// square of edge `size`) on its plane at its pose, seen from the front only (a tag facing away is
/// not drawn), the nearest tag in front of the camera where they overlap. Each pixel (OpenCV
/// convention: centre at integer coordinates, area +-0.5 around it) is the mean of s x s rays
/// (s = supersample) at sub-pixel positions, one in each of s x s cells and one in each of s^2
/// columns and s^2 rows (an edge along a pixel axis is resolved to 1/s^2 px), each ray the exact
/// inverse of the lens model (k1..k6, p1, p2, s1..s4, tilt) at its position; a pixel whose whole
/// area lies in one cell takes that cell's value, one the lens model cannot invert the background.
/// The pixel-corner rays are cached for the last intrinsics used (thread-safe). Throws CameraError
/// for an invalid camera, std::invalid_argument for bad options or a tag id outside tag36h11.
cv::Mat renderTagScene(const calib::Camera& camera, const calib::TagLayout& layout,
                       const TagSceneOptions& options = {});

/// The same scene in colour (CV_8UC3, BGR): surfaces keep their colours; tags and the background
/// are grey. renderTagScene() is its grey conversion (identical values when everything is grey).
cv::Mat renderTagSceneBgr(const calib::Camera& camera, const calib::TagLayout& layout,
                          const TagSceneOptions& options = {});

/// Where the layout's tag corners project through the camera's full lens model (cv::projectPoints),
/// in Tag::corners() order; the reference for detected corners.
std::vector<std::array<cv::Point2d, 4>> projectTagCorners(const calib::Camera& camera, const calib::TagLayout& layout);

/// The camera's lens model applied to normalised image coordinates (x/z, y/z) -> pixel, as
/// cv::projectPoints does it; exposed so tests can check the renderer's model against OpenCV.
cv::Point2d distortNormalised(const calib::Camera& camera, const cv::Point2d& normalised);

}  // namespace kccd::calib
