#include "passes.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>

#include "gl_api.hpp"

namespace kccd::render::detail {
namespace {

void setCamera(const Projection& projection, double near, double far) {
  const std::array<float, 16> m = projection.glMatrix(near, far);
  GL().Viewport(0, 0, projection.pinhole().width, projection.pinhole().height);
  GL().MatrixMode(GL_PROJECTION);
  GL().LoadMatrixf(m.data());
  GL().MatrixMode(GL_MODELVIEW);
  GL().LoadIdentity();
  GL().Enable(GL_CULL_FACE);
  GL().CullFace(GL_BACK);
  GL().FrontFace(GL_CW);  // the projection keeps image rows top-down, which mirrors the winding
  GL().EnableClientState(GL_VERTEX_ARRAY);
}

// Draws a quad over the whole viewport (the camera matrices are restored afterwards).
void fillViewport() {
  GL().MatrixMode(GL_PROJECTION);
  GL().PushMatrix();
  GL().LoadIdentity();
  GL().MatrixMode(GL_MODELVIEW);
  GL().Disable(GL_CULL_FACE);
  const float quad[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  GL().VertexPointer(3, GL_FLOAT, 0, quad);
  GL().DrawArrays(GL_TRIANGLE_FAN, 0, 4);
  GL().Enable(GL_CULL_FACE);
  GL().MatrixMode(GL_PROJECTION);
  GL().PopMatrix();
  GL().MatrixMode(GL_MODELVIEW);
}

void drawTriangles(const Mesh& mesh, const std::vector<float>& vertices) {
  GL().VertexPointer(3, GL_FLOAT, 0, vertices.data());
  GL().DrawElements(GL_TRIANGLES, static_cast<GLsizei>(mesh.triangles.size() * 3), GL_UNSIGNED_INT,
                    mesh.triangles.data());
}

// Draw buffers of the bound framebuffer: the colour attachment, the label attachment, or both.
void drawBuffers(bool colour, bool labels) {
  const GLenum none = GL_NONE;
  const GLenum buffers[] = {colour ? GLenum{GL_COLOR_ATTACHMENT0} : none, labels ? GLenum{GL_COLOR_ATTACHMENT1} : none};
  GL().DrawBuffers(labels ? 2 : 1, buffers);
}

// Clears the label attachment (draw buffer 1) to 0 and the depth buffer to "infinitely far".
void clearLabels() {
  const float zero[4] = {0, 0, 0, 0}, far = 0.0f;  // reversed depth: 0 is infinitely far
  GL().ClearBufferfv(GL_COLOR, 1, zero);
  GL().ClearBufferfv(GL_DEPTH, 0, &far);
}

// Reads the label attachment of the bound framebuffer (CV_8UC1).
cv::Mat readLabels(int w, int h) {
  cv::Mat labels(h, w, CV_8UC1);
  GL().ReadBuffer(GL_COLOR_ATTACHMENT1);
  GL().PixelStorei(GL_PACK_ALIGNMENT, 1);
  GL().ReadPixels(0, 0, w, h, GL_RED, GL_UNSIGNED_BYTE, labels.data);
  GL().ReadBuffer(GL_COLOR_ATTACHMENT0);
  return labels;
}

// The labels of the meshes into the label attachment of the bound framebuffer, depth-tested so
// the nearest surface's label stays whatever the order (surfaces from both sides; reversed depth,
// see the label shader in gl_targets.cpp); leaves the depth test and blending off.
void drawLabelTriangles(const GlTargets& gl, const std::vector<PreparedVolume>& bodies, double near) {
  GL().Disable(GL_BLEND);
  GL().Enable(GL_DEPTH_TEST);
  GL().DepthFunc(GL_GREATER);
  GL().DepthMask(GL_TRUE);
  GL().UseProgram(gl.program);
  GL().Uniform1f(gl.near_location, static_cast<float>(near));
  // Front to back: farther fragments then fail the depth test and write nothing.
  std::vector<const PreparedVolume*> order;
  for (const PreparedVolume& p : bodies)
    if (p.mesh) order.push_back(&p);
  std::sort(order.begin(), order.end(),
            [](const PreparedVolume* a, const PreparedVolume* b) { return a->depth < b->depth; });
  for (const PreparedVolume* p : order) {
    GL().Uniform1ui(gl.label_location, static_cast<GLuint>(p->label));
    if (p->surface) GL().Disable(GL_CULL_FACE);
    drawTriangles(*p->mesh, p->vertices);
    GL().Enable(GL_CULL_FACE);
  }
  GL().UseProgram(0);
  GL().DepthFunc(GL_LESS);
  GL().Disable(GL_DEPTH_TEST);
}

// Opaque volumes, depth-tested, each vertex lit by Lambert's law with the normal averaged over its
// triangles (smooth shading of the tessellated surface).
void drawShaded(const std::vector<const PreparedVolume*>& order, double ambient) {
  GL().Enable(GL_DEPTH_TEST);
  GL().DepthFunc(GL_LESS);
  GL().Disable(GL_BLEND);
  GL().ShadeModel(GL_SMOOTH);
  GL().EnableClientState(GL_COLOR_ARRAY);
  // Light from the camera's upper left (camera frame: x right, y down, z forward), towards the scene.
  const Vec3 to_light = Vec3(-0.45, -0.6, -1.0).normalized();
  std::vector<Vec3> normals;
  std::vector<float> colours;
  for (const PreparedVolume* p : order) {
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
    GL().ColorPointer(4, GL_FLOAT, 0, colours.data());
    GL().VertexPointer(3, GL_FLOAT, 0, p->vertices.data());
    if (p->surface) GL().Disable(GL_CULL_FACE);
    GL().DrawElements(GL_TRIANGLES, static_cast<GLsizei>(m.triangles.size() * 3), GL_UNSIGNED_INT, m.triangles.data());
    GL().Enable(GL_CULL_FACE);
  }
  GL().DisableClientState(GL_COLOR_ARRAY);
  GL().Disable(GL_DEPTH_TEST);
}

// The dirty cells of `out` within `cells` (in cells), as runs along each row of cells.
std::vector<cv::Rect> dirtyCellRuns(const ColourReadBack& out, const cv::Rect& cells) {
  std::vector<cv::Rect> runs;
  const auto dirty = [&](int cx, int cy) { return out.dirty[static_cast<std::size_t>(cy * out.cells_x + cx)] != 0; };
  for (int cy = cells.y; cy < cells.y + cells.height; ++cy)
    for (int cx = cells.x; cx < cells.x + cells.width;) {
      if (!dirty(cx, cy)) {
        ++cx;
        continue;
      }
      const int first = cx;
      while (cx < cells.x + cells.width && dirty(cx, cy)) ++cx;
      runs.emplace_back(first, cy, cx - first, 1);
    }
  return runs;
}

// The cells (in cells) that meet the pixel rectangle `r`.
cv::Rect cellsOf(const cv::Rect& r) {
  constexpr int c = ColourReadBack::kCell;
  if (r.empty()) return {};
  return cv::Rect(cv::Point(r.x / c, r.y / c), cv::Point((r.x + r.width - 1) / c + 1, (r.y + r.height - 1) / c + 1));
}

// Zeros the colour of the bound target in every dirty cell of `out` (transparent quads over the
// whole cells, blending off, camera matrices restored) and marks every cell clean. Cell edges lie
// on pixel edges, so each quad covers its cells' pixel centres and no other.
void clearCells(ColourReadBack& out) {
  constexpr int c = ColourReadBack::kCell;
  GLint viewport[4] = {0, 0, 0, 0};
  GL().GetIntegerv(GL_VIEWPORT, viewport);
  const double w = viewport[2], h = viewport[3];
  // Pixel edges to normalised device coordinates (GL's rows are the image's, see setCamera).
  const auto nx = [&](int x) { return static_cast<float>(2.0 * std::min<double>(x, w) / w - 1.0); };
  const auto ny = [&](int y) { return static_cast<float>(2.0 * std::min<double>(y, h) / h - 1.0); };
  std::vector<float> quads;
  for (const cv::Rect& run : dirtyCellRuns(out, cv::Rect(0, 0, out.cells_x, out.cells_y))) {
    const float x0 = nx(run.x * c), x1 = nx((run.x + run.width) * c), y0 = ny(run.y * c), y1 = ny((run.y + 1) * c);
    quads.insert(quads.end(), {x0, y0, 0, x1, y0, 0, x1, y1, 0, x0, y0, 0, x1, y1, 0, x0, y1, 0});
  }
  std::fill(out.dirty.begin(), out.dirty.end(), 0);
  if (quads.empty()) return;
  GL().MatrixMode(GL_PROJECTION);
  GL().PushMatrix();
  GL().LoadIdentity();
  GL().MatrixMode(GL_MODELVIEW);
  GL().Disable(GL_CULL_FACE);
  GL().Disable(GL_DEPTH_TEST);
  GL().Disable(GL_BLEND);
  GL().Color4f(0, 0, 0, 0);
  GL().VertexPointer(3, GL_FLOAT, 0, quads.data());
  GL().DrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(quads.size() / 3));
  GL().Enable(GL_CULL_FACE);
  GL().MatrixMode(GL_PROJECTION);
  GL().PopMatrix();
  GL().MatrixMode(GL_MODELVIEW);
}

// Marks dirty every cell of `out` whose part of the read-back rectangle holds a non-zero byte.
void markDirtyCells(ColourReadBack& out) {
  constexpr int c = ColourReadBack::kCell;
  const cv::Rect& r = out.rect;
  const cv::Rect cells = cellsOf(r);
  for (int cy = cells.y; cy < cells.y + cells.height; ++cy)
    for (int cx = cells.x; cx < cells.x + cells.width; ++cx) {
      unsigned char& cell = out.dirty[static_cast<std::size_t>(cy * out.cells_x + cx)];
      if (cell) continue;
      const cv::Rect part = cv::Rect(cx * c, cy * c, c, c) & r;
      bool any = false;
      for (int y = part.y; y < part.y + part.height && !any; ++y) {
        const uchar* row = out.image.ptr<uchar>(y, part.x);
        uchar bits = 0;
        for (int k = 0; k < 4 * part.width; ++k) bits |= row[k];
        any = bits != 0;
      }
      cell = any;
    }
}

// The dirty cells within the read-back rectangle as pixel rectangles (runs along each row of
// cells, clipped to it).
std::vector<cv::Rect> dirtyRuns(const ColourReadBack& out) {
  constexpr int c = ColourReadBack::kCell;
  std::vector<cv::Rect> runs;
  for (const cv::Rect& run : dirtyCellRuns(out, cellsOf(out.rect)))
    runs.push_back(cv::Rect(run.x * c, run.y * c, run.width * c, c) & out.rect);
  return runs;
}

// Volumes' vertices, indices and colours (one per volume) gathered for one draw call, drawn in the order added.
struct OutlineBatch {
  std::vector<float> vertices, colours;  // xyz and rgba per vertex
  std::vector<std::uint32_t> indices;

  void add(const std::vector<float>& xyz, const std::vector<std::uint32_t>& index, const std::array<float, 4>& rgba) {
    const auto base = static_cast<std::uint32_t>(vertices.size() / 3);
    vertices.insert(vertices.end(), xyz.begin(), xyz.end());
    for (std::size_t k = 0; k < xyz.size() / 3; ++k) colours.insert(colours.end(), rgba.begin(), rgba.end());
    for (const std::uint32_t i : index) indices.push_back(base + i);
  }
  // Draws the primitives of `mode`. A primitive's vertices share one colour, so interpolating it
  // gives that colour exactly (its gradients are zero). Not GL_FLAT: on llvmpipe a later smooth
  // draw of another program then came out flat-shaded.
  void draw(GLenum mode) const {
    if (indices.empty()) return;
    GL().EnableClientState(GL_COLOR_ARRAY);
    GL().ColorPointer(4, GL_FLOAT, 0, colours.data());
    GL().VertexPointer(3, GL_FLOAT, 0, vertices.data());
    GL().DrawElements(mode, static_cast<GLsizei>(indices.size()), GL_UNSIGNED_INT, indices.data());
    GL().DisableClientState(GL_COLOR_ARRAY);
  }
  void clear() {
    vertices.clear();
    colours.clear();
    indices.clear();
  }
};

}  // namespace

std::vector<cv::Rect> colourRects(const Projection& projection, const std::vector<PreparedVolume>& bodies,
                                  const Style& style, double near) {
  const Pinhole& pin = projection.pinhole();
  const cv::Rect all(0, 0, pin.width, pin.height);
  // Smoothed lines reach half their width and a pixel of coverage beyond the vertices; GL projects
  // in float: four more pixels each way cover both with room to spare.
  const double margin = (style.shaded ? 0.0 : 0.5 * style.outline_width * projection.supersample()) + 4.0;
  std::vector<cv::Rect> rects;
  for (const PreparedVolume& p : bodies) {
    if (p.fills) return {all};
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    bool whole = false;
    auto add = [&](const std::vector<float>& v) {
      for (std::size_t k = 0; k + 2 < v.size(); k += 3) {
        const double z = v[k + 2];
        const double x = pin.fx * v[k] / z + pin.cx, y = pin.fy * v[k + 1] / z + pin.cy;
        // Clipped by the near plane (or not a number, or far off): the clipped polygon may reach any pixel.
        if (!(z > near) || !(std::abs(x) < 1e7 && std::abs(y) < 1e7)) {
          whole = true;
          return;
        }
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    };
    if (p.mesh) add(p.vertices);
    if (p.outlined()) add(p.outline_vertices);
    if (whole) return {all};
    if (!(x0 <= x1)) continue;
    const int left = static_cast<int>(std::floor(x0 - margin)), top = static_cast<int>(std::floor(y0 - margin));
    const int right = static_cast<int>(std::ceil(x1 + margin)), bottom = static_cast<int>(std::ceil(y1 + margin));
    const cv::Rect r = cv::Rect(cv::Point(std::max(left, 0), std::max(top, 0)),
                                cv::Point(std::min(right, pin.width), std::min(bottom, pin.height))) &
                       all;
    if (!r.empty()) rects.push_back(r);
  }
  return rects;
}

void drawColour(GlTargets& gl, const Projection& projection, const RenderOptions& options,
                const std::vector<PreparedVolume>& bodies, const Style& style, Frame& frame, ColourReadBack& out,
                cv::Mat* labels) {
  const auto t0 = std::chrono::steady_clock::now();
  const double near = frame.near, far = frame.far;
  const int w = gl.width, h = gl.height;
  const bool with_labels = labels != nullptr && gl.samples <= 1 && !style.shaded;
  GL().BindFramebuffer(GL_FRAMEBUFFER, gl.samples > 1 ? gl.ms_fbo : gl.resolve_fbo);
  if (gl.samples <= 1) drawBuffers(true, with_labels);
  setCamera(projection, near, far);
  // Only the rectangle that will be read back is cleared and drawn (the labels are read whole):
  // the rasteriser leaves the other tiles alone.
  out.parts = options.crop
                  ? colourRects(projection, bodies, style, near)
                  : std::vector<cv::Rect>{cv::Rect(0, 0, projection.pinhole().width, projection.pinhole().height)};
  cv::Rect rect;
  for (const cv::Rect& r : out.parts) rect |= r;
  if (!with_labels) {
    GL().Enable(GL_SCISSOR_TEST);
    GL().Scissor(rect.x, rect.y, rect.width, rect.height);
  }
  if (out.cells_x !=
      (w + ColourReadBack::kCell - 1) / ColourReadBack::kCell) {  // the first frame: the target is unknown
    out.cells_x = (w + ColourReadBack::kCell - 1) / ColourReadBack::kCell;
    out.cells_y = (h + ColourReadBack::kCell - 1) / ColourReadBack::kCell;
    out.dirty.assign(static_cast<std::size_t>(out.cells_x) * static_cast<std::size_t>(out.cells_y), 1);
  }
  if (!with_labels && !style.shaded && gl.samples <= 1 && options.crop) {
    // The tinted look tests no depth: only the colour is cleared, and only in the cells that may
    // hold a pixel (drawn as transparent quads: llvmpipe clears a scissored rectangle several
    // times slower than it fills one). The target is then zero everywhere, as a clear leaves it.
    GL().Disable(GL_SCISSOR_TEST);
    clearCells(out);
    GL().Enable(GL_SCISSOR_TEST);
  } else {
    GL().ClearColor(0, 0, 0, 0);
    GL().ClearDepth(1.0);
    GL().Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (with_labels) std::fill(out.dirty.begin(), out.dirty.end(), 0);  // cleared whole (no scissor)
  }
  if (with_labels) clearLabels();
  if (style.shaded) {
    std::vector<const PreparedVolume*> all;
    for (const PreparedVolume& p : bodies)
      if (p.mesh) all.push_back(&p);
    drawShaded(all, style.ambient);
  } else {
    GL().Disable(GL_DEPTH_TEST);
    GL().Enable(GL_BLEND);
    // Premultiplied result on a transparent clear; converted to straight alpha after read-back.
    GL().BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    // Back to front; back faces culled, so each convex volume tints a pixel once.
    std::vector<const PreparedVolume*> order;
    for (const PreparedVolume& p : bodies)
      if (p.drawn()) order.push_back(&p);
    std::sort(order.begin(), order.end(),
              [](const PreparedVolume* a, const PreparedVolume* b) { return a->depth > b->depth; });
    // Whether the fill may be the silhouette polygon: a single loop whose vertices all lie beyond
    // the near plane (then its projection is the convex outline of the front faces, unclipped).
    auto polygonFill = [&](const PreparedVolume& p) {
      if (!options.polygon_fill || p.fill.empty()) return false;
      for (const std::uint32_t k : p.silhouette)
        if (!(p.vertices[3 * k + 2] > near)) return false;
      return true;
    };
    if (with_labels) {  // the labels of the nearest surfaces first (see kLabelFragmentShader), then the colour
      drawBuffers(false, true);
      drawLabelTriangles(gl, bodies, near);
      drawBuffers(true, false);
      GL().Enable(GL_BLEND);
    }
    // The tints as premultiplied colours (the blend then multiplies nothing by the source alpha:
    // ~15 % less fill time on llvmpipe than blending straight colours).
    GL().BlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    // Consecutive outlined volumes are filled in one draw call (GL blends a call's triangles in
    // their order, and a colour per volume's vertices is the colour glColor would give: the same
    // pixels for a fraction of the per-call cost on llvmpipe).
    OutlineBatch batch;
    auto flushFills = [&] {
      if (batch.indices.empty()) return;
      GL().Disable(GL_CULL_FACE);  // the outline's winding is the image's, not the mesh's
      batch.draw(GL_TRIANGLES);
      GL().Enable(GL_CULL_FACE);
      batch.clear();
    };
    for (const PreparedVolume* p : order) {
      const cv::Scalar c = p->colour;  // BGR, drawn as GL's RGB (see the read-back)
      const double fa = style.fill_alpha;
      const std::array<float, 4> tint{static_cast<float>(fa * c[0] / 255.0), static_cast<float>(fa * c[1] / 255.0),
                                      static_cast<float>(fa * c[2] / 255.0), static_cast<float>(fa)};
      if (p->outlined()) {
        ++frame.polygon_fills;
        batch.add(p->outline_vertices, p->outline_fill, tint);
        continue;
      }
      flushFills();
      GL().Color4f(tint[0], tint[1], tint[2], tint[3]);
      if (!p->surface && polygonFill(*p)) {
        ++frame.polygon_fills;
        GL().VertexPointer(3, GL_FLOAT, 0, p->vertices.data());
        GL().DrawElements(GL_TRIANGLES, static_cast<GLsizei>(p->fill.size()), GL_UNSIGNED_INT, p->fill.data());
      } else {
        drawTriangles(*p->mesh, p->vertices);
      }
    }
    flushFills();
    GL().BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE,
                           GL_ONE_MINUS_SRC_ALPHA);  // smoothed lines: coverage in alpha
    GL().LineWidth(static_cast<float>(style.outline_width * projection.supersample()));
    GL().Enable(GL_LINE_SMOOTH);  // coverage in alpha, blended like the fill
    GL().Hint(GL_LINE_SMOOTH_HINT, GL_NICEST);
    // Every volume's outline in one draw call, in the same order, each in its own colour.
    for (const PreparedVolume* p : order) {
      const cv::Scalar c = p->colour * 0.7;
      const bool own = p->outlined();
      batch.add(
          own ? p->outline_vertices : p->vertices, own ? p->outline_lines : p->outline,
          {static_cast<float>(c[0] / 255.0), static_cast<float>(c[1] / 255.0), static_cast<float>(c[2] / 255.0), 1.0f});
    }
    batch.draw(GL_LINES);
    GL().Disable(GL_LINE_SMOOTH);
    // Volumes containing the camera tint the whole view, in front of everything else.
    for (const PreparedVolume& p : bodies)
      if (p.fills) {
        const cv::Scalar c = p.colour;
        GL().Color4d(c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, style.fill_alpha);
        fillViewport();
      }
    GL().Disable(GL_BLEND);
  }
  GL().Disable(GL_SCISSOR_TEST);
  if (gl.samples > 1) {
    GL().BindFramebuffer(GL_READ_FRAMEBUFFER, gl.ms_fbo);
    GL().BindFramebuffer(GL_DRAW_FRAMEBUFFER, gl.resolve_fbo);
    drawBuffers(true, false);  // a mask drawn alone before leaves the label attachment selected
    GL().BlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  GL().BindFramebuffer(GL_READ_FRAMEBUFFER, gl.resolve_fbo);
  GL().Finish();
  const auto t1 = std::chrono::steady_clock::now();
  if (out.image.rows != h || out.image.cols != w || out.image.type() != CV_8UC4) {
    out.image = cv::Mat::zeros(h, w, CV_8UC4);
    out.rect = cv::Rect();
  }
  out.image(out.rect).setTo(cv::Scalar::all(0));  // the previous frame's pixels
  out.rect = rect;
  if (!out.rect.empty()) {
    // Colours are drawn with blue in GL's red channel, so the plain RGBA read (llvmpipe's fast
    // path, no swizzle) returns OpenCV's BGRA order. GL's rows are the image's (see setCamera).
    GL().PixelStorei(GL_PACK_ALIGNMENT, 1);
    GL().PixelStorei(GL_PACK_ROW_LENGTH, w);
    GL().ReadPixels(out.rect.x, out.rect.y, out.rect.width, out.rect.height, GL_RGBA, GL_UNSIGNED_BYTE,
                    out.image.ptr<uchar>(out.rect.y, out.rect.x));
    GL().PixelStorei(GL_PACK_ROW_LENGTH, 0);
    // Without multisampling the target's pixels are the ones read: cells holding one are dirty,
    // and only they are handed on to the warp (the read-back is zero in the others).
    if (gl.samples <= 1) {
      markDirtyCells(out);
      out.parts = dirtyRuns(out);
    }
  }
  if (with_labels) *labels = readLabels(w, h);
  GL().BindFramebuffer(GL_FRAMEBUFFER, 0);
  const auto t2 = std::chrono::steady_clock::now();
  frame.times.draw += std::chrono::duration<double>(t1 - t0).count();
  frame.times.read_back += std::chrono::duration<double>(t2 - t1).count();
}

cv::Mat drawMask(GlTargets& gl, const Projection& mask_projection, const std::vector<PreparedVolume>& bodies,
                 double near, double far) {
  const int w = gl.mask_width, h = gl.mask_height;
  GL().BindFramebuffer(GL_FRAMEBUFFER, gl.mask_fbo != 0 ? gl.mask_fbo : gl.resolve_fbo);
  drawBuffers(false, true);
  setCamera(mask_projection, near, far);
  clearLabels();
  drawLabelTriangles(gl, bodies, near);
  GL().Finish();
  cv::Mat mask = readLabels(w, h);
  GL().BindFramebuffer(GL_FRAMEBUFFER, 0);
  return mask;
}

}  // namespace kccd::render::detail
