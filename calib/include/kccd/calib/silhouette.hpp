// The robot's silhouette as a camera sees it, drawn on the CPU from the model's volumes (sphere
// swept convex hulls): the filled mask and points on its outline that know where they lie on the
// robot, so a pose can be fitted to an image's outline of the robot (mask_refine.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/model.hpp"

namespace kccd::calib {

/// A volume placed in the world: the core points of a body at one state, and its radius.
struct PlacedVolume {
  std::vector<Vec3> points;  ///< world coordinates
  double radius = 0.0;
};

/// A triangle mesh placed in the world: what part of the robot looks like (a visual mesh at one
/// state).
struct PlacedMesh {
  std::vector<Vec3> vertices;                           ///< world coordinates
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< indices into vertices
};

/// The volumes of `bodies` (indices into model.bodies; all when empty) at `state`. Throws
/// InputError for a state of the wrong size or a body index out of range.
std::vector<PlacedVolume> placeVolumes(const Model& model, std::span<const double> state,
                                       std::span<const int> bodies = {});

/// A point of the silhouette's outline.
struct OutlinePoint {
  Vec3 world;          ///< the point of the volume whose image it is (first order: it moves with the pose)
  cv::Point2d pixel;   ///< where `camera` projects it
  cv::Point2d normal;  ///< the outline's outward unit normal there, in the image
};

/// A silhouette: the filled mask (255 robot, 0 not) and its outer outline sampled about every
/// `spacing_px` pixels.
struct Silhouette {
  cv::Mat mask;                       ///< CV_8UC1, camera.height x camera.width
  std::vector<OutlinePoint> outline;  ///< points on the union's boundary (inside the image or not)
};

/// The silhouette of `volumes` through `camera` (lens included): each volume's outline is the
/// convex hull of its spheres' rims in undistorted coordinates, exact up to the rim sampling,
/// then distorted; volumes reaching behind the camera are left out. Never throws for a valid
/// camera.
Silhouette drawSilhouette(const Camera& camera, std::span<const PlacedVolume> volumes, double spacing_px = 2.0);

/// The silhouette of `meshes` through `camera` (lens included): every triangle in front of the
/// camera filled (its corners projected through the lens: exact for triangles of a few pixels),
/// the union's outer outline traced and sampled, each outline point the mesh point half a pixel
/// outside the outline pixel's triangle (on its plane), so the outline is not drawn half a pixel
/// thin. Triangles reaching behind the camera are left out. Never throws for a valid camera.
Silhouette drawMeshSilhouette(const Camera& camera, std::span<const PlacedMesh> meshes, double spacing_px = 2.0);

/// Intersection over union of two masks of the same size (non-zero = in); 1 when both are empty.
double maskIou(const cv::Mat& a, const cv::Mat& b);

}  // namespace kccd::calib
