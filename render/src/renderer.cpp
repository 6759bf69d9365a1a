#include "kccd/render/renderer.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "gl_api.hpp"
#include "gl_targets.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/prepare.hpp"
#include "legend.hpp"
#include "passes.hpp"
#include "warp.hpp"

namespace kccd::render {

Renderer::Renderer(const Camera& camera, const RenderOptions& options)
    : Renderer(Projection(camera, options.supersample), options) {}

Renderer::Renderer(const Projection& projection, const RenderOptions& options)
    : options_(options), projection_(projection), context_(GlContext::make()) {
  if (projection.supersample() != options.supersample)
    throw std::invalid_argument("Renderer: the projection's supersample differs from RenderOptions::supersample");
  const Camera& camera = projection_.camera();
  GLint max_renderbuffer = 0, viewport[2] = {0, 0};
  detail::GL().GetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
  detail::GL().GetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
  const int max_w = std::min<int>(max_renderbuffer, viewport[0]), max_h = std::min<int>(max_renderbuffer, viewport[1]);
  auto fits = [&](const Projection& p) { return p.pinhole().width <= max_w && p.pinhole().height <= max_h; };
  if (!fits(projection_)) {
    std::ostringstream msg;
    msg << "the " << camera.width << "x" << camera.height << " image is drawn as a " << projection_.pinhole().width
        << "x" << projection_.pinhole().height << " pinhole image (supersample " << options.supersample
        << "), more than this GL allows (" << max_w << "x" << max_h << "): use a smaller supersample";
    throw CameraError(InputLocation{"camera", 0, 0, "image_width"}, msg.str());
  }
  if (camera.distorted() && options.mask_supersample != options.supersample) {
    auto mask = std::make_unique<Projection>(camera, options.mask_supersample);
    if (fits(*mask)) mask_projection_ = std::move(mask);  // else the mask keeps the colour pass's scale
  }
  const Pinhole& mask = maskProjection().pinhole();
  gl_ = std::make_unique<detail::GlTargets>(projection_.pinhole().width, projection_.pinhole().height,
                                            options.msaa_samples, mask.width, mask.height);
  preparer_ = std::make_unique<FramePreparer>(projection_, maskProjection(), options_);
  colour_warp_ = std::make_unique<detail::ColourWarp>(projection_);
  read_back_ = std::make_unique<detail::ColourReadBack>();
  label_warp_ = std::make_unique<detail::LabelWarp>(maskProjection());
  legend_ = std::make_unique<detail::Legend>(projection_, options_.near);
}

Renderer::~Renderer() {
  context_->makeCurrent();
  gl_.reset();
}

const std::string& Renderer::rendererString() const { return context_->renderer(); }

const MeshCache& Renderer::meshCache() const { return preparer_->meshCache(); }

Frame Renderer::render(std::span<const Volume> volumes, const Style& style, bool want_colour, bool want_mask) {
  return draw(volumes, style, want_colour, want_mask, nullptr);
}

Frame Renderer::renderOnto(cv::Mat& bgr, std::span<const Volume> volumes, const Style& style) {
  const Camera& camera = projection_.camera();
  if (bgr.type() != CV_8UC3 || bgr.cols != camera.width || bgr.rows != camera.height)
    throw std::invalid_argument("Renderer::renderOnto: needs a CV_8UC3 image of the camera's size");
  // Names on the layer and uncropped layers take the layer's way (rare in overlays).
  if (style.labels || !options_.crop) {
    Frame frame = draw(volumes, style, true, false, nullptr);
    compositeOver(bgr, frame.bgra, frame.drawn);
    frame.bgra.release();
    return frame;
  }
  Frame frame = draw(volumes, style, true, false, &bgr);
  again_style_ = style;
  again_frame_ = frame;
  return frame;
}

bool Renderer::canRenderOntoAgain(const Style& style) const { return again_style_ && *again_style_ == style; }

Frame Renderer::renderOntoAgain(cv::Mat& bgr, const Style& style) {
  if (!canRenderOntoAgain(style)) throw std::logic_error("Renderer::renderOntoAgain: the last call drew no such layer");
  const Camera& camera = projection_.camera();
  if (bgr.type() != CV_8UC3 || bgr.cols != camera.width || bgr.rows != camera.height)
    throw std::invalid_argument("Renderer::renderOntoAgain: needs a CV_8UC3 image of the camera's size");
  Frame frame = again_frame_;
  frame.times = FrameTimes{};
  frame.meshes_built = 0;
  blendOnto(bgr, style, frame);
  return frame;
}

void Renderer::blendOnto(cv::Mat& bgr, const Style& style, Frame& frame) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t = Clock::now();
  detail::TileMask tiles(projection_.camera().width, projection_.camera().height);
  // Warped, straightened and blended in one pass; the legend's box is the legend's alone.
  const cv::Rect legend = style.legend ? legend_->legendBox(bgr.size()) : cv::Rect();
  colour_warp_->blendOnto(bgr, read_back_->image, read_back_->parts, tiles, legend);
  const Clock::time_point t_warped = Clock::now();
  if (style.legend) tiles.mark(legend_->compositeLegend(bgr));
  frame.drawn = tiles.runs();
  frame.times.warp = std::chrono::duration<double>(t_warped - t).count();
  frame.times.decorate = std::chrono::duration<double>(Clock::now() - t_warped).count();
}

Frame Renderer::draw(std::span<const Volume> volumes, const Style& style, bool want_colour, bool want_mask,
                     cv::Mat* onto) {
  if (volumes.size() > 255) throw std::invalid_argument("Renderer: at most 255 volumes (8-bit mask labels)");
  const auto t_start = std::chrono::steady_clock::now();
  again_style_.reset();  // this draw replaces the layer
  context_->makeCurrent();
  // Outlines from the cores for the tinted look's colour layer; meshes for the labels, the
  // shaded look, and what the outlines cannot draw.
  const bool outlines = want_colour && !style.shaded && options_.polygon_fill && options_.outline_from_core;
  PreparedFrame prepared = preparer_->prepare(
      volumes, PrepareNeeds{.outlines = outlines, .meshes = want_mask || !outlines, .mask = want_mask});
  const std::vector<PreparedVolume>& bodies = prepared.volumes;
  Frame frame = std::move(prepared.frame);
  // The mask from the colour pass when it can (the overlay look at the colour pass's scale).
  const bool same_pass = want_colour && want_mask && !style.shaded && gl_->samples <= 1 && !mask_projection_;
  cv::Mat labels;
  using Clock = std::chrono::steady_clock;
  const auto seconds = [](Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
  };
  Clock::time_point t = Clock::now();
  frame.times.prepare = seconds(t_start, t);
  if (want_colour) {
    detail::drawColour(*gl_, projection_, options_, bodies, style, frame, *read_back_, same_pass ? &labels : nullptr);
    if (onto) {
      blendOnto(*onto, style, frame);
    } else {
      t = Clock::now();
      detail::TileMask tiles(projection_.camera().width, projection_.camera().height);
      frame.bgra = colour_warp_->apply(read_back_->image, read_back_->parts, tiles);
      const Clock::time_point t_warped = Clock::now();
      tiles.mark(legend_->draw(frame.bgra, volumes, frame.visibility, style));
      if (!options_.crop) tiles.mark(cv::Rect(0, 0, frame.bgra.cols, frame.bgra.rows));
      frame.times.warp = seconds(t, t_warped);
      frame.drawn = tiles.runs();
      frame.times.decorate = seconds(t_warped, Clock::now());
    }
    t = Clock::now();
  }
  if (want_mask) {
    cv::Mat pinhole_labels =
        same_pass ? labels : detail::drawMask(*gl_, maskProjection(), bodies, frame.near, frame.far);
    // A volume containing the camera is the nearest everywhere.
    const auto fill = std::find_if(bodies.begin(), bodies.end(), [](const PreparedVolume& p) { return p.fills; });
    if (fill != bodies.end()) pinhole_labels.setTo(cv::Scalar::all(fill->label));
    std::array<int, 256> counts{};
    frame.mask = label_warp_->apply(pinhole_labels, counts);
    // Each label from the nearest pinhole sample (through a warp) of a mesh drawn a little outside.
    const Projection& mp = maskProjection();
    frame.mask_edge_px = mp.warps() ? std::sqrt(0.5) * mp.stretch() : 0.0;
    double mesh_error = 0.0;
    for (const PreparedVolume& p : bodies)
      if (p.mesh && !p.surface) mesh_error = std::max(mesh_error, p.mesh_error_px);
    frame.mask_edge_px += mesh_error;
    frame.pixels.assign(volumes.size(), 0);
    for (std::size_t i = 0; i < volumes.size(); ++i)
      frame.pixels[i] = counts[static_cast<std::size_t>(bodies[i].label)];
    frame.times.mask = seconds(t, Clock::now());
  }
  // KCCD_RENDER_PROFILE: each frame's stages on stderr (drawColour ends its drawing with glFinish).
  static const bool profile = std::getenv("KCCD_RENDER_PROFILE") != nullptr;
  if (profile) {
    const FrameTimes& ft = frame.times;
    std::fprintf(stderr,
                 "prepare %.2f ms  draw %.2f ms  read-back %.2f ms  warp %.2f ms  decorate %.2f ms  mask %.2f ms\n",
                 1e3 * ft.prepare, 1e3 * ft.draw, 1e3 * ft.read_back, 1e3 * ft.warp, 1e3 * ft.decorate, 1e3 * ft.mask);
  }
  return frame;
}

}  // namespace kccd::render
