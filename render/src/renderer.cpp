#include "kccd/render/renderer.hpp"

#include "kccd/distance.hpp"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace kccd::render {

const char* toString(Visibility visibility) {
  switch (visibility) {
    case Visibility::Drawn: return "drawn";
    case Visibility::FillsView: return "contains the camera";
    case Visibility::Empty: return "no volume";
    case Visibility::NotFinite: return "not finite";
    case Visibility::BehindCamera: return "behind the camera";
    case Visibility::BeyondFar: return "beyond far plane";
    case Visibility::NoMesh: return "no mesh";
  }
  return "?";
}

cv::Scalar statusColour(SafetyStatus status) {
  switch (status) {
    case SafetyStatus::Clear: return {60, 200, 40};
    case SafetyStatus::WithinMargin: return {0, 180, 255};
    case SafetyStatus::Colliding: return {40, 40, 230};
    case SafetyStatus::NoState: return {160, 160, 160};
  }
  return {255, 255, 255};
}

// Labels are drawn by a shader into a one-channel 8-bit target (label / 255, exact in unorm8),
// depth-tested so each pixel keeps the label of the nearest surface whatever the drawing order.
// The depth written is reversed, near / (camera z) in (0, 1] (GL_GREATER, cleared to 0): in the
// float depth buffer it tells surfaces apart to ~1e-7 of their distance whatever the near plane
// (which a volume next to the camera, even outside the view, pulls in close; a conventional
// depth buffer would resolve ~6e-8 z^2 / near). The colour output is unused (that draw buffer
// is off), so the colour layer is drawn afterwards exactly as without labels.
constexpr const char* kLabelVertexShader = R"(#version 330 compatibility
out float camera_z;
void main() {
  gl_Position = ftransform();
  camera_z = gl_Vertex.z;
}
)";
constexpr const char* kLabelFragmentShader = R"(#version 330 compatibility
in float camera_z;
uniform uint label;
uniform float near;
layout(location = 0) out vec4 colour;
layout(location = 1) out vec4 nearest;
void main() {
  colour = vec4(0.0);
  nearest = vec4(float(label) / 255.0, 0.0, 0.0, 0.0);
  gl_FragDepth = near / max(camera_z, near);
}
)";

/// The framebuffers: a multisampled colour target resolved into a plain one, with a second
/// attachment for labels (drawn in the colour pass, or alone for a mask only), and a label target
/// of its own when the mask uses another pinhole scale than the colour layer.
struct Renderer::Gl {
  GLuint ms_fbo = 0, ms_colour = 0;
  GLuint resolve_fbo = 0, resolve_colour = 0, resolve_labels = 0;
  GLuint ms_depth = 0, resolve_depth = 0;  // depth for the shaded (opaque) look
  GLuint mask_fbo = 0, mask_labels = 0, mask_depth = 0;  // only with a separate mask scale
  GLuint program = 0;
  GLint label_location = -1, near_location = -1;
  int samples = 0;
  int width = 0, height = 0;

  static GLuint compile(GLenum type, const char* source) {
    const GLuint shader = glCreateShader(type);
    glShaderSource(shader, 1, &source, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[1024] = {};
      glGetShaderInfoLog(shader, sizeof log, nullptr, log);
      glDeleteShader(shader);
      throw GlContextError(std::string("GL: label shader: ") + log);
    }
    return shader;
  }

  static void check(GLuint fbo, const char* what) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw GlContextError(std::string("GL: ") + what + " framebuffer incomplete (status " + std::to_string(status) + ")");
  }
  static GLuint renderbuffer(GLenum format, int samples, int w, int h) {
    GLuint rb = 0;
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    if (samples > 1)
      glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples, format, w, h);
    else
      glRenderbufferStorage(GL_RENDERBUFFER, format, w, h);
    return rb;
  }

  int mask_width = 0, mask_height = 0;

  Gl(int w, int h, int want_samples, int mw, int mh) : width(w), height(h), mask_width(mw), mask_height(mh) {
    GLint max_samples = 0, max_size = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_size);
    if (std::max({w, h, mw, mh}) > max_size)
      throw GlContextError("GL: image " + std::to_string(std::max(w, mw)) + "x" + std::to_string(std::max(h, mh)) +
                           " exceeds the renderbuffer limit " + std::to_string(max_size));
    samples = want_samples > 1 ? std::min(want_samples, static_cast<int>(max_samples)) : 0;
    resolve_colour = renderbuffer(GL_RGBA8, 0, w, h);
    glGenFramebuffers(1, &resolve_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_colour);
    resolve_depth = renderbuffer(GL_DEPTH_COMPONENT32F, 0, w, h);  // float: labels of near surfaces at any near plane
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, resolve_depth);
    resolve_labels = renderbuffer(GL_R8, 0, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, resolve_labels);
    check(resolve_fbo, "colour");
    if (samples > 1) {
      ms_colour = renderbuffer(GL_RGBA8, samples, w, h);
      glGenFramebuffers(1, &ms_fbo);
      glBindFramebuffer(GL_FRAMEBUFFER, ms_fbo);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, ms_colour);
      ms_depth = renderbuffer(GL_DEPTH_COMPONENT24, samples, w, h);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, ms_depth);
      check(ms_fbo, "multisample colour");
    }
    if (mw != w || mh != h) {
      mask_labels = renderbuffer(GL_R8, 0, mw, mh);
      glGenFramebuffers(1, &mask_fbo);
      glBindFramebuffer(GL_FRAMEBUFFER, mask_fbo);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, mask_labels);
      mask_depth = renderbuffer(GL_DEPTH_COMPONENT32F, 0, mw, mh);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, mask_depth);
      const GLenum buffers[] = {GL_NONE, GL_COLOR_ATTACHMENT1};
      glDrawBuffers(2, buffers);
      glReadBuffer(GL_COLOR_ATTACHMENT1);
      check(mask_fbo, "mask");
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const GLuint vs = compile(GL_VERTEX_SHADER, kLabelVertexShader);
    const GLuint fs = compile(GL_FRAGMENT_SHADER, kLabelFragmentShader);
    program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
      char log[1024] = {};
      glGetProgramInfoLog(program, sizeof log, nullptr, log);
      glDeleteProgram(program);
      throw GlContextError(std::string("GL: label shader: ") + log);
    }
    label_location = glGetUniformLocation(program, "label");
    near_location = glGetUniformLocation(program, "near");
  }
  ~Gl() {
    const GLuint fbos[] = {ms_fbo, resolve_fbo, mask_fbo};
    const GLuint rbs[] = {ms_colour, resolve_colour, resolve_labels, mask_labels, ms_depth, resolve_depth, mask_depth};
    glDeleteFramebuffers(3, fbos);
    glDeleteRenderbuffers(7, rbs);
    glDeleteProgram(program);
  }
};

/// One volume ready to draw: its mesh and the mesh vertices in camera coordinates (float, as
/// uploaded), the silhouette edges seen from the camera, and its depth for sorting.
struct Renderer::Prepared {
  int index = 0;
  SafetyStatus status = SafetyStatus::NoState;
  cv::Scalar colour;      // fill colour (BGR)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // volume frame -> camera
  std::shared_ptr<const Mesh> mesh;
  std::vector<float> vertices;
  std::vector<std::uint32_t> outline;
  // The silhouette edges as one closed loop, wound like the front faces (empty when they do not
  // form a single simple loop).
  std::vector<std::uint32_t> silhouette;
  std::vector<std::uint32_t> fill;  // the silhouette polygon as triangles (see polygonTriangles)
  // The outline computed from the core (RenderOptions::outline_from_core): its corners in camera
  // coordinates on a plane between the clipping planes, as lines and as triangles (empty: none).
  std::vector<Eigen::Vector2d> outline_2d;  // normalised image coordinates
  std::vector<float> outline_vertices;
  std::vector<std::uint32_t> outline_lines, outline_fill;
  bool outlined() const { return !outline_2d.empty(); }  // tint and outline from the core's outline
  bool drawn() const { return mesh || outlined(); }      // in the images (else not drawn, or filling the view)
  double depth = 0.0;
  bool fills = false;     // contains the camera: drawn as a full-view fill, no mesh
  int level = 0;           // sphere tessellation level
  double clearance = 0.0;  // distance from the camera to the mesh (lower bound), when drawn
  double reach = 0.0;      // distance from the camera to the farthest point of the mesh
  bool surface = false;    // a Volume::surface: both sides drawn, no outline
  int label = 0;           // mask label
};

Renderer::Renderer(const Camera& camera, const RenderOptions& options)
    : Renderer(Projection(camera, options.supersample), options) {}

Renderer::Renderer(const Projection& projection, const RenderOptions& options)
    : options_(options),
      projection_(projection),
      context_(GlContext::make()),
      world_to_camera_(projection.camera().worldToCamera()) {
  if (projection.supersample() != options.supersample)
    throw std::invalid_argument("Renderer: the projection's supersample differs from RenderOptions::supersample");
  const Camera& camera = projection_.camera();
  GLint max_renderbuffer = 0, viewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
  const int max_w = std::min<int>(max_renderbuffer, viewport[0]), max_h = std::min<int>(max_renderbuffer, viewport[1]);
  auto fits = [&](const Projection& p) { return p.pinhole().width <= max_w && p.pinhole().height <= max_h; };
  if (!fits(projection_)) {
    std::ostringstream msg;
    msg << "the " << camera.width << "x" << camera.height << " image is drawn as a "
        << projection_.pinhole().width << "x" << projection_.pinhole().height << " pinhole image (supersample "
        << options.supersample << "), more than this GL allows (" << max_w << "x" << max_h << "): use a smaller supersample";
    throw CameraError(InputLocation{"camera", 0, 0, "image_width"}, msg.str());
  }
  if (camera.distorted() && options.mask_supersample != options.supersample) {
    auto mask = std::make_unique<Projection>(camera, options.mask_supersample);
    if (fits(*mask)) mask_projection_ = std::move(mask);  // else the mask keeps the colour pass's scale
  }
  const Pinhole& mask = maskProjection().pinhole();
  gl_ = std::make_unique<Gl>(projection_.pinhole().width, projection_.pinhole().height, options.msaa_samples, mask.width,
                             mask.height);
}

Renderer::~Renderer() {
  context_->makeCurrent();
  gl_.reset();
}

const std::string& Renderer::rendererString() const { return context_->renderer(); }

namespace {

// The silhouette of a convex mesh seen from the camera: the edges between a front and a back
// triangle, each directed as its front triangle runs along it, chained into one loop. Seen from
// a camera in front of every vertex, the front triangles cover exactly the convex polygon this
// loop bounds, so the polygon fills the same pixels with far fewer triangles. Leaves `loop`
// empty when the edges do not chain into one simple loop (near-degenerate views).
void silhouetteLoop(const Mesh& m, const std::vector<char>& front, const std::vector<std::uint32_t>& outline,
                    std::vector<std::uint32_t>& loop) {
  loop.clear();
  const std::size_t n = outline.size() / 2;
  if (n < 3) return;
  // Directed edges from -> to, sorted by `from` for the walk.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> next;
  next.reserve(n);
  for (const auto& e : m.edges) {
    if (front[e[2]] == front[e[3]]) continue;
    const auto& t = m.triangles[front[e[2]] ? e[2] : e[3]];
    const bool forward = (t[0] == e[0] && t[1] == e[1]) || (t[1] == e[0] && t[2] == e[1]) || (t[2] == e[0] && t[0] == e[1]);
    next.emplace_back(forward ? e[0] : e[1], forward ? e[1] : e[0]);
  }
  std::sort(next.begin(), next.end());
  for (std::size_t k = 1; k < next.size(); ++k)
    if (next[k].first == next[k - 1].first) return;  // a vertex with two outgoing edges
  const std::uint32_t start = next.front().first;
  std::uint32_t at = start;
  loop.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    loop.push_back(at);
    const auto it = std::lower_bound(next.begin(), next.end(), std::make_pair(at, std::uint32_t{0}));
    if (it == next.end() || it->first != at) {
      loop.clear();
      return;
    }
    at = it->second;
    if (at == start && k + 1 != n) {  // closed early: more than one loop
      loop.clear();
      return;
    }
  }
  if (at != start) loop.clear();
}

// A convex polygon (vertex indices in order) as triangles of about equal aspect: one triangle on
// three vertices a third of the way round each other, and each remaining arc split in the middle.
// The same pixels as a fan, but large triangles cover whole tiles of the rasteriser.
void polygonTriangles(const std::vector<std::uint32_t>& loop, std::vector<std::uint32_t>& out) {
  out.clear();
  const std::size_t n = loop.size();
  if (n < 3) return;
  auto arc = [&](auto&& self, std::size_t a, std::size_t b) -> void {  // vertices a..b (b may be n: vertex 0)
    if (b - a < 2) return;
    const std::size_t m = (a + b) / 2;
    out.insert(out.end(), {loop[a], loop[m], loop[b % n]});
    self(self, a, m);
    self(self, m, b);
  };
  const std::size_t i = n / 3, j = 2 * n / 3;
  out.insert(out.end(), {loop[0], loop[i], loop[j]});
  arc(arc, 0, i);
  arc(arc, i, j);
  arc(arc, j, n);
}

}  // namespace

void Renderer::prepare(std::span<const Volume> volumes, std::vector<Prepared>& out, Frame& frame, bool outlines,
                       bool need_meshes) {
  cache_.nextFrame();
  const std::uint64_t built_before = cache_.built();
  const Camera& cam = projection_.camera();
  const double focal = std::max(cam.camera_matrix(0, 0), cam.camera_matrix(1, 1));
  out.resize(volumes.size());
  frame.visibility.assign(volumes.size(), Visibility::Empty);
  std::vector<Vec3> cam_points;
  std::vector<MeshRequest> requests;
  std::vector<std::size_t> requested;  // the volume of each request
  const Vec3 origin = Vec3::Zero();
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    const Volume& v = volumes[i];
    Prepared& p = out[i];
    p.index = static_cast<int>(i);
    p.status = v.status;
    p.colour = v.colour[0] >= 0 ? v.colour : statusColour(v.status);
    p.mesh.reset();
    p.vertices.clear();
    p.outline.clear();
    p.fills = false;
    p.silhouette.clear();
    p.fill.clear();
    p.outline_2d.clear();
    p.outline_vertices.clear();
    p.outline_lines.clear();
    p.outline_fill.clear();
    p.surface = false;
    p.label = v.mask_label >= 0 ? std::min(v.mask_label, 255) : static_cast<int>(i) + 1;
    Visibility& visibility = frame.visibility[i];
    if (v.surface) {
      prepareSurface(v, p, visibility);
      if (visibility == Visibility::Drawn) frame.triangles += static_cast<int>(p.mesh->triangles.size());
      continue;
    }
    if (v.points.empty()) continue;
    // Tessellation fine enough that the circumscribed sphere polytope lies at most
    // tolerance_px outside the true surface, as seen from the closest point of the volume.
    const Pose to_camera = world_to_camera_ * v.pose;
    p.rotation = to_camera.linear();
    cam_points.clear();
    double zmin = 1e300, zmax = -1e300;
    Vec3 centre = Vec3::Zero();
    for (const Vec3& w : v.points) {
      cam_points.push_back(to_camera * w);
      zmin = std::min(zmin, cam_points.back().z());
      zmax = std::max(zmax, cam_points.back().z());
      centre += cam_points.back();
    }
    centre /= static_cast<double>(cam_points.size());
    const double r = std::max(v.radius, options_.min_radius);
    double spread = 0.0;
    for (const Vec3& c : cam_points) spread = std::max(spread, (c - centre).norm());
    if (!allFinite(cam_points) || !std::isfinite(v.radius) || !std::isfinite(spread + r) || !std::isfinite(centre.norm())) {
      visibility = Visibility::NotFinite;
      continue;
    }
    p.depth = centre.norm();
    if (zmax + r <= 0.0) {
      visibility = Visibility::BehindCamera;
      continue;
    }
    p.reach = p.depth + spread + r;
    if (p.reach * 1.01 > kMaxDrawDistance) {
      visibility = Visibility::BeyondFar;
      continue;
    }
    zmin -= r;
    int level = options_.max_level;
    if (zmin > options_.near) {
      const double r_px = focal * r / zmin;
      for (int l = 1; l < options_.max_level; ++l)
        if ((spherePolytope(l).scale - 1.0) * r_px <= options_.tolerance_px) {
          level = l;
          break;
        }
    }
    // How near the mesh comes to the camera: the volume's distance less the tessellation's
    // outward error. A volume (nearly) containing the camera covers the whole view.
    const DistanceResult d = distance(SschView{cam_points, r}, SschView{std::span<const Vec3>(&origin, 1), 0.0});
    p.clearance = d.status == GjkStatus::InvalidInput ? 0.0 : d.distance - (spherePolytope(level).scale - 1.0) * r;
    if (p.clearance <= 1e-4) {
      p.fills = true;
      visibility = Visibility::FillsView;
      continue;
    }
    p.level = level;
    // The outline straight from the core when the volume lies beyond the near plane; the mesh
    // when a mask or the shaded look needs it, or the outline cannot be had.
    if (outlines && sschOutline(cam_points, r, OutlineOptions{.focal_px = focal, .tolerance_px = options_.tolerance_px,
                                                              .min_depth = options_.near},
                                p.outline_2d) &&
        p.outline_2d.size() >= 3) {  // (fewer corners: an image thinner than the tolerance, drawn from the mesh)
      visibility = Visibility::Drawn;
      ++frame.outlines;
      if (!need_meshes) continue;
    } else {
      p.outline_2d.clear();
    }
    requests.push_back(MeshRequest{v.points, v.radius, level, options_.min_radius});
    requested.push_back(i);
  }
  // The meshes (those not cached built in parallel), then per volume in parallel: the vertices
  // in camera coordinates, the silhouette edges and their loop.
  const std::vector<MeshCache::Found> meshes = cache_.getAll(requests);
  for (std::size_t k = 0; k < requested.size(); ++k) {
    Prepared& p = out[requested[k]];
    if (!meshes[k].mesh) {  // qhull on extreme coordinates
      if (!p.outlined() || need_meshes) frame.visibility[requested[k]] = Visibility::NoMesh;  // (not in the mask)
      continue;
    }
    p.mesh = meshes[k].mesh;
    frame.visibility[requested[k]] = Visibility::Drawn;
    if (meshes[k].built) frame.hull_input += p.mesh->hull_input;
    frame.max_level = std::max(frame.max_level, p.level);
    frame.triangles += static_cast<int>(p.mesh->triangles.size());
  }
  cv::parallel_for_(cv::Range(0, static_cast<int>(requested.size())), [&](const cv::Range& range) {
    std::vector<char> front;
    for (int k = range.start; k < range.end; ++k) {
      Prepared& p = out[requested[static_cast<std::size_t>(k)]];
      if (!p.mesh) continue;
      const Mesh& m = *p.mesh;
      const Pose to_camera = world_to_camera_ * volumes[static_cast<std::size_t>(p.index)].pose;
      p.vertices.resize(m.vertices.size() * 3);
      for (std::size_t j = 0; j < m.vertices.size(); ++j) {
        const Vec3 c = to_camera * m.vertices[j];
        p.vertices[3 * j] = static_cast<float>(c.x());
        p.vertices[3 * j + 1] = static_cast<float>(c.y());
        p.vertices[3 * j + 2] = static_cast<float>(c.z());
      }
      if (p.outlined()) continue;  // drawn from its outline: the mesh is for the labels only
      // Silhouette edges: one neighbouring triangle faces the camera (at the origin), the other not.
      front.resize(m.triangles.size());
      for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const Vec3 n = to_camera.linear() * m.normals[t];
        const Vec3 a = to_camera * m.vertices[m.triangles[t][0]];
        front[t] = n.dot(a) < 0.0;
      }
      for (const auto& e : m.edges)
        if (front[e[2]] != front[e[3]]) p.outline.insert(p.outline.end(), {e[0], e[1]});
      silhouetteLoop(m, front, p.outline, p.silhouette);
      polygonTriangles(p.silhouette, p.fill);
    }
  });
  frame.meshes_built = static_cast<int>(cache_.built() - built_before);
  // Clipping planes that clip no drawn mesh: the near plane closer than the nearest mesh
  // anywhere in the view frustum, the far plane beyond the farthest one.
  frame.near = options_.near;
  frame.far = options_.far;
  for (const Projection* pr : {static_cast<const Projection*>(&projection_), &maskProjection()}) {
    const Pinhole& ph = pr->pinhole();
    const double tx = std::max(ph.cx + 0.5, ph.width - ph.cx - 0.5) / ph.fx;
    const double ty = std::max(ph.cy + 0.5, ph.height - ph.cy - 0.5) / ph.fy;
    const double corner = std::sqrt(1.0 + tx * tx + ty * ty);  // frustum corner at unit depth
    for (const Prepared& p : out)
      if (p.drawn()) frame.near = std::min(frame.near, 0.5 * p.clearance / corner);
  }
  for (const Prepared& p : out)
    if (p.drawn()) frame.far = std::max(frame.far, 1.01 * p.reach);
  // Outlines on a plane between the clipping planes (drawn without depth test, so only their
  // rays matter).
  const double z = std::sqrt(frame.near * frame.far);
  for (Prepared& p : out) {
    if (!p.outlined()) continue;
    const std::size_t n = p.outline_2d.size();
    p.outline_vertices.resize(3 * n);
    for (std::size_t k = 0; k < n; ++k) {
      p.outline_vertices[3 * k] = static_cast<float>(p.outline_2d[k].x() * z);
      p.outline_vertices[3 * k + 1] = static_cast<float>(p.outline_2d[k].y() * z);
      p.outline_vertices[3 * k + 2] = static_cast<float>(z);
    }
    std::vector<std::uint32_t> loop(n);
    for (std::size_t k = 0; k < n; ++k) {
      loop[k] = static_cast<std::uint32_t>(k);
      p.outline_lines.insert(p.outline_lines.end(), {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>((k + 1) % n)});
    }
    polygonTriangles(loop, p.outline_fill);
    frame.triangles += static_cast<int>(p.outline_fill.size() / 3);
  }
}

namespace {
// Distance from the origin to the triangle abc (closest point by the triangle's Voronoi regions).
double originToTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = -a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a.norm();
  const Vec3 bp = -b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (a + d1 / (d1 - d3) * ab).norm();
  const Vec3 cp = -c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (a + d2 / (d2 - d6) * ac).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)).norm();
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0.0)) return std::min({a.norm(), b.norm(), c.norm()});
  return (a + (vb / denom) * ab + (vc / denom) * ac).norm();
}
}  // namespace

// A surface (appearance mesh): its vertices in camera coordinates and how near it comes to the
// camera (for the near plane).
void Renderer::prepareSurface(const Volume& v, Prepared& p, Visibility& visibility) {
  const Mesh& m = *v.surface;
  if (m.triangles.empty()) return;  // Empty
  const Pose to_camera = world_to_camera_ * v.pose;
  p.rotation = to_camera.linear();
  p.vertices.resize(m.vertices.size() * 3);
  Vec3 centre = Vec3::Zero();
  double zmax = -1e300, nearest = 1e300, farthest = 0.0;
  for (std::size_t k = 0; k < m.vertices.size(); ++k) {
    const Vec3 c = to_camera * m.vertices[k];
    if (!c.allFinite()) {
      visibility = Visibility::NotFinite;
      return;
    }
    p.vertices[3 * k] = static_cast<float>(c.x());
    p.vertices[3 * k + 1] = static_cast<float>(c.y());
    p.vertices[3 * k + 2] = static_cast<float>(c.z());
    centre += c;
    zmax = std::max(zmax, c.z());
    nearest = std::min(nearest, c.norm());
    farthest = std::max(farthest, c.norm());
  }
  // The nearest point of the surface: a triangle comes no nearer than its nearest vertex less
  // its longest edge; only triangles that could beat the best distance so far are measured.
  double clearance = nearest;
  auto camera_point = [&](std::uint32_t k) {
    return Vec3(p.vertices[3 * k], p.vertices[3 * k + 1], p.vertices[3 * k + 2]);
  };
  for (const auto& t : m.triangles) {
    const Vec3 a = camera_point(t[0]), b = camera_point(t[1]), c = camera_point(t[2]);
    const double edge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (std::min({a.norm(), b.norm(), c.norm()}) - edge < clearance)
      clearance = std::min(clearance, originToTriangle(a, b, c));
  }
  if (zmax <= 0.0) {
    visibility = Visibility::BehindCamera;
    return;
  }
  if (farthest * 1.01 > kMaxDrawDistance) {
    visibility = Visibility::BeyondFar;
    return;
  }
  p.depth = (centre / static_cast<double>(m.vertices.size())).norm();
  p.reach = farthest;
  p.clearance = std::max(0.999 * clearance, 1e-4);  // appearance only: a mesh reaching the camera is clipped
  p.mesh = v.surface;
  p.surface = true;
  visibility = Visibility::Drawn;
}

namespace {

void setCamera(const Projection& projection, double near, double far) {
  const std::array<float, 16> m = projection.glMatrix(near, far);
  glViewport(0, 0, projection.pinhole().width, projection.pinhole().height);
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixf(m.data());
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glFrontFace(GL_CW);  // the projection keeps image rows top-down, which mirrors the winding
  glEnableClientState(GL_VERTEX_ARRAY);
}

// Draws a quad over the whole viewport (the camera matrices are restored afterwards).
void fillViewport() {
  glMatrixMode(GL_PROJECTION);
  glPushMatrix();
  glLoadIdentity();
  glMatrixMode(GL_MODELVIEW);
  glDisable(GL_CULL_FACE);
  const float quad[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  glVertexPointer(3, GL_FLOAT, 0, quad);
  glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
  glEnable(GL_CULL_FACE);
  glMatrixMode(GL_PROJECTION);
  glPopMatrix();
  glMatrixMode(GL_MODELVIEW);
}

void drawTriangles(const Mesh& mesh, const std::vector<float>& vertices) {
  glVertexPointer(3, GL_FLOAT, 0, vertices.data());
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(mesh.triangles.size() * 3), GL_UNSIGNED_INT, mesh.triangles.data());
}

// Draw buffers of the bound framebuffer: the colour attachment, the label attachment, or both.
void drawBuffers(bool colour, bool labels) {
  const GLenum none = GL_NONE;
  const GLenum buffers[] = {colour ? GLenum{GL_COLOR_ATTACHMENT0} : none, labels ? GLenum{GL_COLOR_ATTACHMENT1} : none};
  glDrawBuffers(labels ? 2 : 1, buffers);
}

// Clears the label attachment (draw buffer 1) to 0 and the depth buffer to "infinitely far".
void clearLabels() {
  const float zero[4] = {0, 0, 0, 0}, far = 0.0f;  // reversed depth: 0 is infinitely far
  glClearBufferfv(GL_COLOR, 1, zero);
  glClearBufferfv(GL_DEPTH, 0, &far);
}

// Reads the label attachment of the bound framebuffer (CV_8UC1).
cv::Mat readLabels(int w, int h) {
  cv::Mat labels(h, w, CV_8UC1);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, w, h, GL_RED, GL_UNSIGNED_BYTE, labels.data);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  return labels;
}

}  // namespace

cv::Mat Renderer::drawColour(const std::vector<Prepared>& bodies, const Style& style, Frame& frame, cv::Mat* labels) {
  const double near = frame.near, far = frame.far;
  const int w = gl_->width, h = gl_->height;
  const bool with_labels = labels != nullptr && gl_->samples <= 1 && !style.shaded;
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->samples > 1 ? gl_->ms_fbo : gl_->resolve_fbo);
  if (gl_->samples <= 1) drawBuffers(true, with_labels);
  setCamera(projection_, near, far);
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (with_labels) clearLabels();
  if (style.shaded) {
    std::vector<const Prepared*> all;
    for (const Prepared& p : bodies)
      if (p.mesh) all.push_back(&p);
    drawShaded(all, style.ambient);
  } else {
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  // Premultiplied result on a transparent clear; converted to straight alpha after read-back.
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  // Back to front; back faces culled, so each convex volume tints a pixel once.
  std::vector<const Prepared*> order;
  for (const Prepared& p : bodies)
    if (p.drawn()) order.push_back(&p);
  std::sort(order.begin(), order.end(), [](const Prepared* a, const Prepared* b) { return a->depth > b->depth; });
  // Whether the fill may be the silhouette polygon: a single loop whose vertices all lie beyond
  // the near plane (then its projection is the convex outline of the front faces, unclipped).
  auto polygonFill = [&](const Prepared& p) {
    if (!options_.polygon_fill || p.fill.empty()) return false;
    for (const std::uint32_t k : p.silhouette)
      if (!(p.vertices[3 * k + 2] > near)) return false;
    return true;
  };
  if (with_labels) {  // the labels of the nearest surfaces first (see kLabelFragmentShader), then the colour
    drawBuffers(false, true);
    drawLabelTriangles(bodies, near);
    drawBuffers(true, false);
    glEnable(GL_BLEND);
  }
  // The tints as premultiplied colours (the blend then multiplies nothing by the source alpha:
  // ~15 % less fill time on llvmpipe than blending straight colours).
  glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  for (const Prepared* p : order) {
    const cv::Scalar c = p->colour;  // BGR, drawn as GL's RGB (see the read-back)
    const double fa = style.fill_alpha;
    glColor4d(fa * c[0] / 255.0, fa * c[1] / 255.0, fa * c[2] / 255.0, fa);
    if (p->outlined()) {
      ++frame.polygon_fills;
      glDisable(GL_CULL_FACE);  // the outline's winding is the image's, not the mesh's
      glVertexPointer(3, GL_FLOAT, 0, p->outline_vertices.data());
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(p->outline_fill.size()), GL_UNSIGNED_INT, p->outline_fill.data());
      glEnable(GL_CULL_FACE);
    } else if (!p->surface && polygonFill(*p)) {
      ++frame.polygon_fills;
      glVertexPointer(3, GL_FLOAT, 0, p->vertices.data());
      glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(p->fill.size()), GL_UNSIGNED_INT, p->fill.data());
    } else {
      drawTriangles(*p->mesh, p->vertices);
    }
  }
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);  // smoothed lines: coverage in alpha
  glLineWidth(static_cast<float>(style.outline_width * projection_.supersample()));
  glEnable(GL_LINE_SMOOTH);  // coverage in alpha, blended like the fill
  glHint(GL_LINE_SMOOTH_HINT, GL_NICEST);
  for (const Prepared* p : order) {
    const cv::Scalar c = p->colour * 0.7;
    glColor4d(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, 1.0);
    const bool own = p->outlined();
    glVertexPointer(3, GL_FLOAT, 0, own ? p->outline_vertices.data() : p->vertices.data());
    const std::vector<std::uint32_t>& lines = own ? p->outline_lines : p->outline;
    glDrawElements(GL_LINES, static_cast<GLsizei>(lines.size()), GL_UNSIGNED_INT, lines.data());
  }
  glDisable(GL_LINE_SMOOTH);
  // Volumes containing the camera tint the whole view, in front of everything else.
  for (const Prepared& p : bodies)
    if (p.fills) {
      const cv::Scalar c = p.colour;
      glColor4d(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, style.fill_alpha);
      fillViewport();
    }
  glDisable(GL_BLEND);
  }
  if (gl_->samples > 1) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gl_->ms_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, gl_->resolve_fbo);
    drawBuffers(true, false);  // a mask drawn alone before leaves the label attachment selected
    glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, gl_->resolve_fbo);
  cv::Mat image(h, w, CV_8UC4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glFinish();
  // Colours are drawn with blue in GL's red channel, so the plain RGBA read (llvmpipe's fast
  // path, no swizzle) returns OpenCV's BGRA order.
  glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, image.data);
  if (with_labels) *labels = readLabels(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return image;
}

// The labels of the meshes into the label attachment of the bound framebuffer, depth-tested so
// the nearest surface's label stays whatever the order (surfaces from both sides; reversed depth,
// see kLabelFragmentShader); leaves the depth test and blending off.
void Renderer::drawLabelTriangles(const std::vector<Prepared>& bodies, double near) {
  glDisable(GL_BLEND);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glUseProgram(gl_->program);
  glUniform1f(gl_->near_location, static_cast<float>(near));
  // Front to back: farther fragments then fail the depth test and write nothing.
  std::vector<const Prepared*> order;
  for (const Prepared& p : bodies)
    if (p.mesh) order.push_back(&p);
  std::sort(order.begin(), order.end(), [](const Prepared* a, const Prepared* b) { return a->depth < b->depth; });
  for (const Prepared* p : order) {
    glUniform1ui(gl_->label_location, static_cast<GLuint>(p->label));
    if (p->surface) glDisable(GL_CULL_FACE);
    drawTriangles(*p->mesh, p->vertices);
    glEnable(GL_CULL_FACE);
  }
  glUseProgram(0);
  glDepthFunc(GL_LESS);
  glDisable(GL_DEPTH_TEST);
}

// The labels alone (a mask without the colour layer, or with the shaded look or multisampling):
// the label attachment of the colour target, or the mask's own target at its own scale.
cv::Mat Renderer::drawMask(const std::vector<Prepared>& bodies, double near, double far) {
  const int w = gl_->mask_width, h = gl_->mask_height;
  glBindFramebuffer(GL_FRAMEBUFFER, gl_->mask_fbo != 0 ? gl_->mask_fbo : gl_->resolve_fbo);
  drawBuffers(false, true);
  setCamera(maskProjection(), near, far);
  clearLabels();
  drawLabelTriangles(bodies, near);
  glFinish();
  cv::Mat mask = readLabels(w, h);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return mask;
}

// Opaque volumes, depth-tested, each vertex lit by Lambert's law with the normal averaged over its
// triangles (smooth shading of the tessellated surface).
void Renderer::drawShaded(const std::vector<const Prepared*>& order, double ambient) {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_BLEND);
  glShadeModel(GL_SMOOTH);
  glEnableClientState(GL_COLOR_ARRAY);
  // Light from the camera's upper left (camera frame: x right, y down, z forward), towards the scene.
  const Vec3 to_light = Vec3(-0.45, -0.6, -1.0).normalized();
  std::vector<Vec3> normals;
  std::vector<float> colours;
  for (const Prepared* p : order) {
    const Mesh& m = *p->mesh;
    normals.assign(m.vertices.size(), Vec3::Zero());
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
      for (const std::uint32_t k : m.triangles[t]) normals[k] += m.normals[t];
    colours.resize(m.vertices.size() * 4);
    for (std::size_t k = 0; k < m.vertices.size(); ++k) {
      Vec3 n = (p->rotation * normals[k]).normalized();
      // A little rim darkening where the surface turns away from the camera (edges read as edges).
      const Vec3 view = -Vec3(p->vertices[3 * k], p->vertices[3 * k + 1], p->vertices[3 * k + 2]).normalized();
      if (p->surface && n.dot(view) < 0.0) n = -n;  // both sides of a surface are lit
      const double lambert = std::max(0.0, n.dot(to_light));
      const double facing = std::clamp(n.dot(view), 0.0, 1.0);
      const double shade = (ambient + (1.0 - ambient) * lambert) * (0.75 + 0.25 * std::sqrt(facing));
      for (int c = 0; c < 3; ++c) colours[4 * k + c] = static_cast<float>(std::min(1.0, p->colour[c] / 255.0 * shade));
      colours[4 * k + 3] = 1.0f;
    }
    glColorPointer(4, GL_FLOAT, 0, colours.data());
    glVertexPointer(3, GL_FLOAT, 0, p->vertices.data());
    if (p->surface) glDisable(GL_CULL_FACE);
    glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(m.triangles.size() * 3), GL_UNSIGNED_INT, m.triangles.data());
    glEnable(GL_CULL_FACE);
  }
  glDisableClientState(GL_COLOR_ARRAY);
  glDisable(GL_DEPTH_TEST);
}

namespace {

// Per row of a warp's y map, the source rows its samples may read: the extremes' floors, widened
// by a row each way for the fixed-point rounding and the bilinear neighbour (empty: first > second).
// Samples above row -1 or below row `source_rows` (e.g. the far-off marks of pixels the lens
// model cannot invert) read nothing (the constant border) and are left out.
std::vector<std::pair<int, int>> sourceRows(const cv::Mat& map_y, int source_rows) {
  std::vector<std::pair<int, int>> rows(static_cast<std::size_t>(map_y.rows), {0, -1});
  for (int y = 0; y < map_y.rows; ++y) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (int x = 0; x < map_y.cols; ++x) {
      const float v = map_y.at<float>(y, x);
      if (v > -2.0f && v < static_cast<float>(source_rows) + 1.0f) lo = std::min(lo, v), hi = std::max(hi, v);
    }
    if (lo <= hi) rows[static_cast<std::size_t>(y)] = {static_cast<int>(std::floor(lo)) - 1, static_cast<int>(std::floor(hi)) + 2};
  }
  return rows;
}

// Which rows of an image hold a non-zero byte, as prefix counts (rows + 1 entries), to ask of
// any range of rows whether something is drawn in it.
struct DrawnRows {
  std::vector<int> prefix;
  explicit DrawnRows(const cv::Mat& image) : prefix(static_cast<std::size_t>(image.rows) + 1, 0) {
    const std::size_t bytes = image.cols * image.elemSize();
    cv::parallel_for_(cv::Range(0, image.rows), [&](const cv::Range& r) {
      for (int y = r.start; y < r.end; ++y) {
        const uchar* row = image.ptr<uchar>(y);
        uchar any = 0;
        for (std::size_t x = 0; x < bytes; ++x) any |= row[x];
        prefix[static_cast<std::size_t>(y) + 1] = any != 0;
      }
    });
    for (std::size_t y = 1; y < prefix.size(); ++y) prefix[y] += prefix[y - 1];
  }
  bool any(std::pair<int, int> rows) const {
    const int n = static_cast<int>(prefix.size()) - 1;
    const int lo = std::clamp(rows.first, 0, n), hi = std::clamp(rows.second + 1, 0, n);
    return lo < hi && prefix[static_cast<std::size_t>(hi)] > prefix[static_cast<std::size_t>(lo)];
  }
};

// Warps `src` into `dst` (the maps' size, src's type; fixed-point maps, map_b may be empty) in
// parallel runs of a few rows and calls after(rows, warped) on each run while it is in cache.
// Output rows whose samples (`source`, from sourceRows) read only empty rows of `src` are cleared
// instead of warped: what the warp would give them (zeros, the constant border).
template <class Fn>
void warpByRows(const cv::Mat& src, cv::Mat& dst, const cv::Mat& map_a, const cv::Mat& map_b, int interpolation,
                const std::vector<std::pair<int, int>>& source, Fn&& after) {
  const DrawnRows drawn(src);
  dst.create(map_a.rows, map_a.cols, src.type());
  constexpr int kBlock = 8;
  cv::parallel_for_(cv::Range(0, (dst.rows + kBlock - 1) / kBlock), [&](const cv::Range& blocks) {
    for (int b = blocks.start; b < blocks.end; ++b) {
      const int y1 = std::min(dst.rows, (b + 1) * kBlock);
      for (int y = b * kBlock; y < y1;) {
        const bool any = drawn.any(source[static_cast<std::size_t>(y)]);
        int end = y + 1;
        while (end < y1 && drawn.any(source[static_cast<std::size_t>(end)]) == any) ++end;
        cv::Mat out = dst.rowRange(y, end);
        if (any)
          cv::remap(src, out, map_a.rowRange(y, end), map_b.empty() ? cv::Mat() : map_b.rowRange(y, end), interpolation,
                    cv::BORDER_CONSTANT, cv::Scalar::all(0));
        else
          out.setTo(cv::Scalar::all(0));
        after(out, any);
        y = end;
      }
    }
  });
}

}  // namespace

Frame Renderer::render(std::span<const Volume> volumes, const Style& style, bool want_colour, bool want_mask) {
  if (volumes.size() > 255) throw std::invalid_argument("Renderer: at most 255 volumes (8-bit mask labels)");
  context_->makeCurrent();
  Frame frame;
  std::vector<Prepared> bodies;
  static const bool profile = std::getenv("KCCD_RENDER_PROFILE") != nullptr;
  auto tick = [last = std::chrono::steady_clock::now()](const char* what) mutable {
    if (!profile) return;
    glFinish();
    const auto now = std::chrono::steady_clock::now();
    std::fprintf(stderr, "%s %.2f ms  ", what, std::chrono::duration<double, std::milli>(now - last).count());
    last = now;
  };
  // Outlines from the cores for the tinted look's colour layer; meshes for the labels, the
  // shaded look, and what the outlines cannot draw.
  const bool outlines = want_colour && !style.shaded && options_.polygon_fill && options_.outline_from_core;
  prepare(volumes, bodies, frame, outlines, want_mask || !outlines);
  tick("prepare");
  // The mask from the colour pass when it can (the overlay look at the colour pass's scale).
  const bool same_pass = want_colour && want_mask && !style.shaded && gl_->samples <= 1 && !mask_projection_;
  cv::Mat labels;
  if (want_colour) {
    cv::Mat premultiplied = drawColour(bodies, style, frame, same_pass ? &labels : nullptr);
    tick("colour+readback");
    // Straight alpha: colour / alpha, through a table.
    static const std::vector<uchar> unpremultiply = [] {
      std::vector<uchar> t(256 * 256);
      for (int a = 1; a < 256; ++a)
        for (int c = 0; c < 256; ++c) t[a * 256 + c] = static_cast<uchar>(std::min(255, (c * 255 + a / 2) / a));
      return t;
    }();
    auto straighten = [&](cv::Mat rows) {
      for (int y = 0; y < rows.rows; ++y) {
        uchar* px = rows.ptr<uchar>(y);
        for (int x = 0; x < rows.cols; ++x, px += 4) {
          const uchar* t = &unpremultiply[px[3] * 256];
          if (px[3] != 255 && px[3] != 0) px[0] = t[px[0]], px[1] = t[px[1]], px[2] = t[px[2]];
        }
      }
    };
    if (projection_.warps()) {
      if (fixed_map_a_.empty()) {  // fixed-point maps: remap's fast path (1/32 px steps)
        cv::convertMaps(projection_.mapX(), projection_.mapY(), fixed_map_a_, fixed_map_b_, CV_16SC2);
        source_rows_ = sourceRows(projection_.mapY(), projection_.pinhole().height);
      }
      // Straightened run by run while in cache; rows the warp clears need nothing.
      warpByRows(premultiplied, frame.bgra, fixed_map_a_, fixed_map_b_, cv::INTER_LINEAR, source_rows_,
                 [&](const cv::Mat& rows, bool warped) {
                   if (warped) straighten(rows);
                 });
    } else {
      frame.bgra = premultiplied;
      cv::parallel_for_(cv::Range(0, frame.bgra.rows),
                        [&](const cv::Range& rows) { straighten(frame.bgra.rowRange(rows.start, rows.end)); });
    }
    tick("warp+unpremultiply");
    decorate(frame.bgra, volumes, frame.visibility, style);
    tick("decorate");
  }
  if (want_mask) {
    cv::Mat pinhole_labels = same_pass ? labels : drawMask(bodies, frame.near, frame.far);
    // A volume containing the camera is the nearest everywhere.
    const auto fill = std::find_if(bodies.begin(), bodies.end(), [](const Prepared& p) { return p.fills; });
    const int fill_label = fill != bodies.end() ? fill->label : -1;
    const Projection& mp = maskProjection();
    if (mp.warps() && mask_map_.empty()) {  // nearest pinhole pixel per output pixel, as integers
      cv::Mat unused;
      cv::convertMaps(mp.mapX(), mp.mapY(), mask_map_, unused, CV_16SC2, true);
      mask_source_rows_ = sourceRows(mp.mapY(), mp.pinhole().height);
    }
    if (fill_label >= 0) pinhole_labels.setTo(cv::Scalar::all(fill_label));
    // The labels at the nearest pinhole pixel of each output pixel (0 outside the pinhole image)
    // and the pixels per label, in runs of rows (rows reading only unlabelled pinhole rows are
    // cleared and counted as background).
    std::array<int, 256> counts{};
    std::mutex counts_mutex;
    auto count = [&](const cv::Mat& rows) {
      std::array<std::array<int, 256>, 4> local{};  // four histograms: fewer store-to-load stalls
      for (int v = 0; v < rows.rows; ++v) {
        const uchar* row = rows.ptr<uchar>(v);
        for (int u = 0; u < rows.cols; ++u) ++local[static_cast<std::size_t>(u & 3)][row[u]];
      }
      const std::lock_guard lock(counts_mutex);
      for (const auto& h : local)
        for (std::size_t k = 0; k < h.size(); ++k) counts[k] += h[k];
    };
    if (mp.warps()) {
      warpByRows(pinhole_labels, frame.mask, mask_map_, cv::Mat(), cv::INTER_NEAREST, mask_source_rows_,
                 [&](const cv::Mat& rows, bool warped) {
                   if (warped) {
                     count(rows);
                   } else {  // cleared: background
                     const std::lock_guard lock(counts_mutex);
                     counts[0] += rows.rows * rows.cols;
                   }
                 });
    } else {
      frame.mask = pinhole_labels;
      cv::parallel_for_(cv::Range(0, frame.mask.rows), [&](const cv::Range& r) { count(frame.mask.rowRange(r.start, r.end)); });
    }
    tick("mask");
    frame.pixels.assign(volumes.size(), 0);
    for (std::size_t i = 0; i < volumes.size(); ++i) frame.pixels[i] = counts[static_cast<std::size_t>(bodies[i].label)];
  }
  if (profile) std::fprintf(stderr, "\n");
  return frame;
}

void Renderer::decorate(cv::Mat& bgra, std::span<const Volume> volumes, const std::vector<Visibility>& visibility,
                        const Style& style) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = std::clamp(bgra.rows / 900.0, 0.35, 1.0);
  const int thick = std::max(1, static_cast<int>(std::lround(scale * 2)));
  auto text = [&](const std::string& s, cv::Point at) {
    cv::putText(bgra, s, at, font, scale, cv::Scalar(0, 0, 0, 255), thick + 2, cv::LINE_AA);
    cv::putText(bgra, s, at, font, scale, cv::Scalar(255, 255, 255, 255), thick, cv::LINE_AA);
  };
  if (style.labels) {
    for (std::size_t i = 0; i < volumes.size(); ++i) {
      const Volume& v = volumes[i];
      if (visibility[i] != Visibility::Drawn || v.label.empty() || v.points.empty()) continue;
      Vec3 centre = Vec3::Zero();
      for (const Vec3& p : v.points) centre += p;
      centre = v.pose * (centre / static_cast<double>(v.points.size()));
      if ((world_to_camera_ * centre).z() <= options_.near) continue;
      const Eigen::Vector2d px = projection_.project(centre);
      // Centres far outside the image have no visible label (and would overflow int).
      if (!(px.x() > -bgra.cols && px.x() < 2.0 * bgra.cols && px.y() > -bgra.rows && px.y() < 2.0 * bgra.rows)) continue;
      int baseline = 0;
      const cv::Size size = cv::getTextSize(v.label, font, scale, thick, &baseline);
      text(v.label, cv::Point(static_cast<int>(px.x()) - size.width / 2, static_cast<int>(px.y()) + size.height / 2));
    }
  }
  if (style.legend) {
    // Drawn once per image size and copied afterwards.
    if (legend_.empty() || legend_rows_ != bgra.rows) {
      legend_rows_ = bgra.rows;
      legend_ = drawLegend(scale, thick);
      cv::Mat alpha;
      cv::extractChannel(legend_, alpha, 3);
      legend_box_ = cv::boundingRect(alpha);
    }
    const cv::Rect box = legend_box_ & cv::Rect(0, 0, bgra.cols, bgra.rows);
    if (!box.empty()) legend_(box).copyTo(bgra(box));  // an image a few pixels high shows none of it
  }
}

cv::Mat Renderer::drawLegend(double scale, int thick) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  auto text = [&](cv::Mat& img, const std::string& s, cv::Point at) {
    cv::putText(img, s, at, font, scale, cv::Scalar(0, 0, 0, 255), thick + 2, cv::LINE_AA);
    cv::putText(img, s, at, font, scale, cv::Scalar(255, 255, 255, 255), thick, cv::LINE_AA);
  };
  cv::Mat bgra;
  {
    const SafetyStatus all[] = {SafetyStatus::Clear, SafetyStatus::WithinMargin, SafetyStatus::Colliding,
                                SafetyStatus::NoState};
    const char* names[] = {"clear", "within margin", "colliding", "no state"};
    int baseline = 0;
    const cv::Size line = cv::getTextSize("within margin", font, scale, thick, &baseline);
    const int pad = std::max(3, line.height / 2), row = line.height + 2 * pad;
    const cv::Rect box(pad, pad, line.width + row + 3 * pad, 4 * row + pad);
    bgra = cv::Mat::zeros(box.br().y, box.br().x, CV_8UC4);
    bgra(box).setTo(cv::Scalar(30, 30, 30, 170));
    for (int i = 0; i < 4; ++i) {
      const int y = box.y + pad + i * row;
      const cv::Scalar c = statusColour(all[i]);
      cv::rectangle(bgra, cv::Rect(box.x + pad, y + pad / 2, row - pad, row - pad), cv::Scalar(c[0], c[1], c[2], 255),
                    cv::FILLED);
      text(bgra, names[i], cv::Point(box.x + row + pad, y + line.height + pad / 2));
    }
  }
  return bgra;
}

}  // namespace kccd::render
