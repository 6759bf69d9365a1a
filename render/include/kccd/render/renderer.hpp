// Drawing SSCH volumes off-screen as the camera sees them: a straight-alpha BGRA layer for
// compositing and an 8-bit label mask.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/render/projection.hpp"
#include "kccd/render/gl_context.hpp"
#include "kccd/safety_status.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "kccd/render/ssch_outline.hpp"

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
  double ambient = 0.35;       ///< shaded: the unlit fraction of the colour
};

/// Renderer settings fixed at construction.
struct RenderOptions {
  double supersample = 1.0;    ///< pinhole image scale (1..4); > 1 keeps thin slivers through the warp
  /// Pinhole scale of the mask when the camera distorts: the warp samples the mask at the nearest
  /// pinhole pixel, so label edges are within 1/(2 s) px. At the colour pass's scale (the default)
  /// the labels go into a second attachment of the colour pass's framebuffer, drawn just before
  /// the colour; another scale (e.g. 2 for ground truth) draws them into a framebuffer of its own.
  double mask_supersample = 1.0;
  /// Multisampling of the colour layer (0 or 1: off; at most 4 on llvmpipe). Off by default:
  /// on llvmpipe 4x MSAA costs ~5x the frame time, and the outline, drawn as smoothed lines on
  /// top of the fill edges, already gives anti-aliased silhouettes.
  int msaa_samples = 0;        ///< colour layer multisampling (0 or 1: off; at most 4 on llvmpipe)
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
  double tolerance_px = 0.5;   ///< largest outward error of the sphere tessellation, output pixels
  int max_level = 3;           ///< finest sphere tessellation (level 3: 642 vertices, 0.3 % outward)
  double min_radius = kMinDrawRadius;  ///< volumes thinner than this are drawn this thick (metres)
  /// Clipping planes, metres along the optical axis. Per frame, the near plane moves closer
  /// when a volume comes nearer to the camera than this, and the far plane moves out to the
  /// farthest volume (up to kMaxDrawDistance), so no drawn volume is clipped by them.
  double near = 0.05;
  double far = 100.0;
};

/// What render() produced: the layer (CV_8UC4, BGRA, straight alpha: PNG viewers and
/// compositing expect it), the mask (CV_8UC1: 0 background, i + 1 for the nearest volume i,
/// sampled at pixel centres), and per volume the mask pixels it owns.
struct Frame {
  cv::Mat bgra;
  cv::Mat mask;
  std::vector<int> pixels;
  std::vector<Visibility> visibility;  ///< per volume
  double near = 0.0, far = 0.0;       ///< the clipping planes used
  int meshes_built = 0;   ///< meshes built in this frame (the others came from the cache)
  int triangles = 0;      ///< triangles drawn: meshes (colour or labels) and outline polygons
  int polygon_fills = 0;  ///< volumes whose tint was drawn as their silhouette polygon (RenderOptions::polygon_fill)
  int outlines = 0;       ///< of those, volumes drawn from their outline computed from the core (RenderOptions::outline_from_core)
  int hull_input = 0;     ///< points passed to qhull for the meshes built in this frame
  int max_level = 0;      ///< finest sphere tessellation used
};

/// Draws volumes with one GL context (made current on the constructing thread; use one
/// Renderer per thread). Meshes are cached by exact volume shape across frames.
class Renderer {
 public:
  /// Creates the GL context and the framebuffers; throws GlContextError or CameraError (also
  /// when the pinhole image exceeds this GL's renderbuffer or viewport limit; the mask pass then
  /// falls back to the colour pass's scale before giving up).
  explicit Renderer(const Camera& camera, const RenderOptions& options = {});
  /// The same with the colour pass's projection made once elsewhere, e.g. shared by the renderers
  /// of several threads (a copy shares its read-only distortion maps, whose set-up dominates the
  /// construction). Its supersample must be options.supersample (std::invalid_argument otherwise).
  Renderer(const Projection& projection, const RenderOptions& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders the colour layer (when `want_colour`) and the mask (when `want_mask`).
  Frame render(std::span<const Volume> volumes, const Style& style = {}, bool want_colour = true,
               bool want_mask = true);

  const std::string& rendererString() const;
  const Projection& projection() const { return projection_; }
  const Projection& maskProjection() const { return mask_projection_ ? *mask_projection_ : projection_; }
  const MeshCache& meshCache() const { return cache_; }

 private:
  struct Gl;
  struct Prepared;
  void prepare(std::span<const Volume> volumes, std::vector<Prepared>& out, Frame& frame, bool outlines, bool need_meshes);
  void prepareSurface(const Volume& v, Prepared& p, Visibility& visibility);
  cv::Mat drawColour(const std::vector<Prepared>& bodies, const Style& style, Frame& frame, cv::Mat* labels = nullptr);
  cv::Mat drawMask(const std::vector<Prepared>& bodies, double near, double far);
  void drawLabelTriangles(const std::vector<Prepared>& bodies, double near);
  static void drawShaded(const std::vector<const Prepared*>& order, double ambient);
  void decorate(cv::Mat& bgra, std::span<const Volume> volumes, const std::vector<Visibility>& visibility,
                const Style& style);
  static cv::Mat drawLegend(double scale, int thick);

  RenderOptions options_;
  Projection projection_;
  std::unique_ptr<Projection> mask_projection_;  // when the mask uses another pinhole scale
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<Gl> gl_;
  MeshCache cache_;
  Pose world_to_camera_;
  cv::Mat fixed_map_a_, fixed_map_b_, mask_map_;  // remap tables in fixed point
  std::vector<std::pair<int, int>> source_rows_, mask_source_rows_;  // per output row, the pinhole rows its warp reads
  cv::Mat legend_;
  cv::Rect legend_box_;
  int legend_rows_ = 0;
};

}  // namespace kccd::render
