// The CPU half of drawing a frame, without GL: which volumes the camera sees and how (mesh,
// outline from the core, filling the view, or not drawn), their geometry in camera coordinates
// as it is uploaded, and the clipping planes that clip none of them.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "kccd/render/mesh.hpp"
#include "kccd/render/mesh_cache.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/render_types.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/types.hpp"

namespace kccd::render {

/// One volume ready to draw: its mesh and the mesh vertices in camera coordinates (float, as
/// uploaded), the silhouette edges seen from the camera, or its outline computed from the core.
struct PreparedVolume {
  int index = 0;                                           ///< its place in the frame's volumes
  SafetyStatus status = SafetyStatus::NoState;             ///< the volume's status
  cv::Scalar colour;                                       ///< fill colour (BGR)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< volume frame -> camera
  std::shared_ptr<const Mesh> mesh;                        ///< its mesh (null: none drawn)
  std::vector<float> vertices;                             ///< mesh vertices in camera coordinates, x y z each
  std::vector<std::uint32_t> outline;                      ///< silhouette edges, two vertex indices each
  /// The silhouette edges as one closed loop, wound like the front faces (empty when they do not
  /// form a single simple loop).
  std::vector<std::uint32_t> silhouette;
  std::vector<std::uint32_t> fill;  ///< the silhouette polygon as triangles
  /// The outline computed from the core (RenderOptions::outline_from_core), its corners in
  /// normalised image coordinates (empty: none).
  std::vector<Eigen::Vector2d> outline_2d;
  std::vector<float> outline_vertices;  ///< those corners in camera coordinates, on a plane between the clipping planes
  std::vector<std::uint32_t> outline_lines;  ///< the outline as line segments (index pairs)
  std::vector<std::uint32_t> outline_fill;   ///< the outline polygon as triangles
  double depth = 0.0;                        ///< distance from the camera to its centre (drawing order)
  bool fills = false;                        ///< contains the camera: drawn as a full-view fill, no mesh
  int level = 0;                             ///< sphere tessellation level
  /// How far, at most, its mesh shows outside the true volume in the camera image, camera pixels
  /// (0 for surfaces, infinite when the volume reaches the camera's plane).
  double mesh_error_px = 0.0;
  double clearance = 0.0;  ///< distance from the camera to the mesh (lower bound), when drawn
  double reach = 0.0;      ///< distance from the camera to the farthest point of the mesh
  bool surface = false;    ///< a Volume::surface: both sides drawn, no outline
  int label = 0;           ///< mask label

  /// Tint and outline come from the core's outline.
  bool outlined() const { return !outline_2d.empty(); }
  /// In the images (else not drawn, or filling the view).
  bool drawn() const { return mesh || outlined(); }
};

/// What a frame needs prepared.
struct PrepareNeeds {
  bool outlines = true;  ///< outlines from the cores where they can be had (the tinted colour layer)
  bool meshes = true;    ///< meshes also for outlined volumes (the mask, the shaded look)
  /// A mask is drawn: meshes fine enough for the mask's scale (tolerance_px / mask supersample).
  bool mask = false;
};

/// A prepared frame: per volume what to draw, and the frame's visibility, clipping planes and
/// counters filled in (its images empty).
struct PreparedFrame {
  std::vector<PreparedVolume> volumes;
  Frame frame;
};

/// Prepares the frames of one camera: the volumes' visibility, tessellation level, meshes (from
/// its cache, those missing built in parallel), silhouettes or outlines, and clipping planes
/// that clip no drawn volume in either pass's view.
class FramePreparer {
 public:
  /// For the colour pass seen through `colour` and the mask pass through `mask` (may be the same
  /// object; both must outlive the preparer), with the renderer's settings.
  FramePreparer(const Projection& colour, const Projection& mask, const RenderOptions& options);

  /// The volumes prepared for drawing (at most what `needs` asks; see PrepareNeeds).
  PreparedFrame prepare(std::span<const Volume> volumes, const PrepareNeeds& needs);

  /// The meshes kept across frames.
  const MeshCache& meshCache() const { return cache_; }

 private:
  void prepareSurface(const Volume& v, PreparedVolume& p, Visibility& visibility) const;

  const Projection& colour_;
  const Projection& mask_;
  RenderOptions options_;
  Pose world_to_camera_;
  MeshCache cache_;
};

}  // namespace kccd::render
