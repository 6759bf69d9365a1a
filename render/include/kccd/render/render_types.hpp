// What the renderer takes and gives: volumes in, a frame out, with the look of the colour layer
// and the settings fixed at construction. Plain data; kccd/render/renderer.hpp draws them.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/render/mesh.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/types.hpp"

namespace kccd::render {

/// The fill colour of a status as BGR (OpenCV order): green clear, amber within the margin, red
/// colliding (or an unsafe query status), grey when no state is known.
cv::Scalar statusColour(SafetyStatus status);

/// How a volume ended up in a frame. Only Drawn and FillsView volumes appear in the images.
enum class Visibility : std::uint8_t {
  Drawn,         ///< drawn as its mesh (possibly outside the image: see Frame::pixels)
  FillsView,     ///< contains the camera (or comes within 0.1 mm of it): fills the whole view
  Empty,         ///< no core points
  NotFinite,     ///< a NaN or infinite coordinate or radius (overflow): not drawn
  BehindCamera,  ///< entirely behind the camera: not drawn
  BeyondFar,     ///< reaches farther than kMaxDrawDistance from the camera: not drawn
  NoMesh,        ///< its mesh could not be built: not drawn
};
/// "drawn", "contains the camera", "no volume", "not finite", "behind the camera",
/// "beyond far plane", "no mesh".
const char* toString(Visibility visibility);

/// Volumes reaching farther than this from the camera (metres) are not drawn (float vertices
/// and the depth range stop being meaningful); nearer ones move the far plane out as needed.
inline constexpr double kMaxDrawDistance = 1e6;

/// One volume to draw: core points in the volume's own frame, placed in the world by `pose`
/// (the mesh is cached by the points and radius, so a volume that only moves keeps its mesh).
struct Volume {
  std::span<const Vec3> points;
  double radius = 0.0;
  SafetyStatus status = SafetyStatus::NoState;
  std::string label;  ///< shown with Style::labels
  Pose pose = Pose::Identity();
  /// BGR fill colour overriding the status colour (used when colour[0] >= 0), e.g. for Style::shaded.
  cv::Scalar colour{-1, -1, -1, -1};
  /// A triangle mesh drawn instead of the SSCH (appearance, e.g. a link's visual geometry; see
  /// surfaceMesh): placed by `pose` like the points, both sides drawn, no outline. `points`
  /// stays empty.
  std::shared_ptr<const Mesh> surface;
  /// The mask label of this volume (0..255; 0 hides what lies behind it without a label of its
  /// own); -1: its index + 1. Frame::pixels[i] counts the pixels of volume i's label.
  int mask_label = -1;
};

/// The look of the colour layer.
struct Style {
  double fill_alpha = 0.35;    ///< opacity of the fill
  double outline_width = 2.0;  ///< outline width in output pixels (opaque, anti-aliased: smoothed lines)
  bool labels = false;         ///< body names at the projected volume centres
  bool legend = true;          ///< colour legend in the top-left corner
  /// Opaque, lit volumes instead of the tinted overlay look: depth-tested, smooth (Gouraud) Lambert
  /// shading by a light at the camera's upper left; fill_alpha and outline_width are not used.
  bool shaded = false;
  double ambient = 0.35;  ///< shaded: the unlit fraction of the colour
  bool operator==(const Style&) const = default;
};

/// Renderer settings fixed at construction.
struct RenderOptions {
  double supersample = 1.0;  ///< pinhole image scale (1..4); > 1 keeps thin slivers through the warp
  /// Pinhole scale of the mask when the camera distorts: the warp takes each label from the
  /// nearest pinhole pixel, which lies within sqrt(2)/2 pinhole pixels of the exact point, and the
  /// meshes for a mask are tessellated to tolerance_px / s (Frame::mask_edge_px is the bound that
  /// results: about 1 px at 1, under 0.5 px at 3 for a mild lens). At the colour pass's scale (the default)
  /// the labels go into a second attachment of the colour pass's framebuffer, drawn just before
  /// the colour; another scale (e.g. 2 for ground truth) draws them into a framebuffer of its own.
  double mask_supersample = 1.0;
  /// Multisampling of the colour layer (0 or 1: off; at most 4 on llvmpipe). Off by default:
  /// on llvmpipe 4x MSAA costs ~5x the frame time, and the outline, drawn as smoothed lines on
  /// top of the fill edges, already gives anti-aliased silhouettes.
  int msaa_samples = 0;  ///< colour layer multisampling (0 or 1: off; at most 4 on llvmpipe)
  /// Fill each volume's tint as the polygon its silhouette edges bound (a few tens of triangles)
  /// instead of its front triangles (hundreds to thousands): the same pixels, since the
  /// silhouette of a convex mesh seen from a camera in front of it bounds exactly the projection
  /// of its front faces. Volumes whose silhouette is not one simple loop or that reach behind the
  /// near plane keep the triangles. Off: always the triangles (for comparison).
  bool polygon_fill = true;
  /// In the tinted look, draw each volume's tint and outline from its outline computed straight
  /// from the core points (see sschOutline: it contains the image and lies at most tolerance_px
  /// outside), so a colour layer needs no mesh; meshes are built only for masks, the shaded look
  /// and volumes reaching nearer than `near`. Needs polygon_fill. Off: from the mesh's silhouette.
  bool outline_from_core = true;
  /// Clear, draw, read back, warp and hand on (Frame::drawn) only the rectangles the volumes and
  /// the legend cover; the layer is the same bit for bit. Off: the whole image (for comparison).
  bool crop = true;
  double tolerance_px = 0.5;  ///< largest outward error of the sphere tessellation, output pixels
  int max_level = 3;          ///< finest sphere tessellation (level 3: 642 vertices, 0.3 % outward)
  int mask_max_level = 4;     ///< finest tessellation when a mask is drawn (level 4: 2562 vertices, 0.08 % outward)
  double min_radius = kMinDrawRadius;  ///< volumes thinner than this are drawn this thick (metres)
  /// Clipping planes, metres along the optical axis. Per frame, the near plane moves closer
  /// when a volume comes nearer to the camera than this, and the far plane moves out to the
  /// farthest volume (up to kMaxDrawDistance), so no drawn volume is clipped by them.
  double near = 0.05;
  double far = 100.0;
  /// How SSCH meshes are built (SschMeshing::Hull: the previous qhull construction, for comparisons).
  SschMeshing meshing = SschMeshing::Direct;
};

/// Where one render() spent its time, seconds (wall clock on the calling thread).
struct FrameTimes {
  double prepare = 0.0;    ///< volumes to meshes and outlines, clipping planes
  double draw = 0.0;       ///< GL drawing, to its end (glFinish)
  double read_back = 0.0;  ///< the colour layer's pixels out of GL
  double warp = 0.0;       ///< the distortion warp and straight alpha
  double decorate = 0.0;   ///< legend and labels
  double mask = 0.0;       ///< the mask pass, its warp and counts
};

/// What render() produced: the layer (CV_8UC4, BGRA, straight alpha: PNG viewers and
/// compositing expect it), the mask (CV_8UC1: 0 background, i + 1 for the nearest volume i,
/// sampled at pixel centres), and per volume the mask pixels it owns.
struct Frame {
  cv::Mat bgra;
  /// Disjoint rectangles of `bgra` that hold every drawn pixel (the volumes', the legend's):
  /// outside them the layer is transparent (all zero), so compositing may skip the rest. None
  /// when nothing is drawn.
  std::vector<cv::Rect> drawn;
  FrameTimes times;
  cv::Mat mask;
  std::vector<int> pixels;
  std::vector<Visibility> visibility;  ///< per volume
  double near = 0.0, far = 0.0;        ///< the clipping planes used
  int meshes_built = 0;                ///< meshes built in this frame (the others came from the cache)
  int triangles = 0;                   ///< triangles drawn: meshes (colour or labels) and outline polygons
  int polygon_fills = 0;  ///< volumes whose tint was drawn as their silhouette polygon (RenderOptions::polygon_fill)
  int outlines =
      0;  ///< of those, volumes drawn from their outline computed from the core (RenderOptions::outline_from_core)
  int hull_input = 0;  ///< points passed to qhull for the meshes built in this frame
  int max_level = 0;   ///< finest sphere tessellation used
  /// With a mask: how far from its centre, at most, the point lies whose label a mask pixel shows,
  /// camera pixels (the nearest pinhole sample through the warp, plus the meshes' outward error).
  /// Each label's region thus lies within this of the exact pixel-centre labels of the volumes as
  /// drawn; infinite when a volume reaches the camera's plane.
  double mask_edge_px = 0.0;
};

}  // namespace kccd::render
