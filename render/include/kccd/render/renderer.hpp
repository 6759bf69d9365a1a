// Drawing SSCH volumes off-screen as the camera sees them: a straight-alpha BGRA layer for
// compositing and an 8-bit label mask.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>

#include "kccd/render/gl_context.hpp"
#include "kccd/render/mesh_cache.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/render_types.hpp"
#include "kccd/render/ssch_mesh.hpp"
#include "kccd/render/ssch_outline.hpp"
#include "kccd/safety_status.hpp"

namespace kccd::render {

class FramePreparer;
namespace detail {
class GlTargets;
class ColourWarp;
struct ColourReadBack;
class LabelWarp;
class Legend;
}  // namespace detail

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
  /// Renders the colour layer straight onto `bgr` (CV_8UC3, the camera image's size; else
  /// std::invalid_argument): the pixels compositeOver(bgr, layer, drawn) gives for render()'s
  /// layer, without making the layer (Frame::bgra stays empty; Frame::drawn says where it drew).
  Frame renderOnto(cv::Mat& bgr, std::span<const Volume> volumes, const Style& style = {});
  /// Whether the last call drew a layer that renderOntoAgain() can put onto another image: a
  /// renderOnto() in `style` that blended in the warp's pass (cropped, no names).
  bool canRenderOntoAgain(const Style& style) const;
  /// The last renderOnto()'s layer (the same volumes, the same style) onto another `bgr`, without
  /// drawing it again: the pixels that renderOnto() with those volumes gives, and its Frame (with
  /// this call's Frame::drawn and times). Throws std::logic_error unless canRenderOntoAgain(style).
  Frame renderOntoAgain(cv::Mat& bgr, const Style& style);

  /// The GL renderer's name (GL_RENDERER), e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  const std::string& rendererString() const;
  /// The colour pass's projection.
  const Projection& projection() const { return projection_; }
  /// The mask pass's projection (the colour pass's unless the mask has a scale of its own).
  const Projection& maskProjection() const { return mask_projection_ ? *mask_projection_ : projection_; }
  /// The meshes kept across frames.
  const MeshCache& meshCache() const;

 private:
  Frame draw(std::span<const Volume> volumes, const Style& style, bool want_colour, bool want_mask, cv::Mat* onto);
  // The read-back layer warped and blended onto `bgr`, the legend's box from the cached legend.
  void blendOnto(cv::Mat& bgr, const Style& style, Frame& frame);

  RenderOptions options_;
  Projection projection_;
  std::unique_ptr<Projection> mask_projection_;  // when the mask uses another pinhole scale
  std::unique_ptr<GlContext> context_;
  std::unique_ptr<detail::GlTargets> gl_;
  std::unique_ptr<FramePreparer> preparer_;
  std::unique_ptr<detail::ColourWarp> colour_warp_;
  std::unique_ptr<detail::ColourReadBack> read_back_;  // the colour target's pixels, kept between frames
  std::unique_ptr<detail::LabelWarp> label_warp_;
  std::unique_ptr<detail::Legend> legend_;
  // The last renderOnto() that blended in the warp's pass: its style and its Frame (no images).
  std::optional<Style> again_style_;
  Frame again_frame_;
};

}  // namespace kccd::render
