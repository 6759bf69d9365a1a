// The renderer's draw passes (internal): the colour layer (tinted or shaded) and the label mask,
// drawn from prepared volumes into the GL targets and read back. The context must be current.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "gl_targets.hpp"
#include "kccd/render/prepare.hpp"
#include "kccd/render/projection.hpp"
#include "kccd/render/render_types.hpp"

namespace kccd::render::detail {

/// The colour layer's pinhole image, kept from frame to frame so that only what is drawn is read
/// back: `image` (CV_8UC4, BGRA, premultiplied alpha, the pinhole size) is zero outside `rect`,
/// and outside the union of `parts` (which `rect` bounds).
struct ColourReadBack {
  cv::Mat image;
  cv::Rect rect;
  std::vector<cv::Rect> parts;
  /// Cells of kCell x kCell pinhole pixels (row-major) of the colour target that may hold a
  /// non-zero pixel: what was read back non-zero, and what an earlier clear did not reach. The
  /// next tinted frame clears these cells alone (the rest of the target is zero already).
  static constexpr int kCell = 16;
  std::vector<unsigned char> dirty;
  int cells_x = 0, cells_y = 0;
};

/// Pinhole rectangles that hold every pixel the colour pass draws of `bodies`, one per drawn
/// volume (its mesh and outline vertices projected, widened by the smoothed outline's width and a
/// few pixels for GL's float arithmetic): the whole image alone when a volume fills the view or
/// reaches the near plane.
std::vector<cv::Rect> colourRects(const Projection& projection, const std::vector<PreparedVolume>& bodies,
                                  const Style& style, double near);

/// The colour layer of the pinhole image through `projection`, between frame.near and frame.far,
/// into `out`: only the rectangle bounding colourRects() is read back, the rest of out.image cleared where the previous
/// frame's rectangle was; counts polygon fills and times the drawing and the read-back into
/// `frame`. With `labels` (and no multisampling, not shaded) the mask labels are drawn in the same
/// pass, just before the colour, and read into *labels (the whole pinhole image).
void drawColour(GlTargets& gl, const Projection& projection, const RenderOptions& options,
                const std::vector<PreparedVolume>& bodies, const Style& style, Frame& frame, ColourReadBack& out,
                cv::Mat* labels = nullptr);

/// The labels alone (a mask without the colour layer, or with the shaded look or multisampling)
/// through the mask pass's projection (CV_8UC1, the pinhole image): the label attachment of the
/// colour target, or the mask's own target at its own scale.
cv::Mat drawMask(GlTargets& gl, const Projection& mask_projection, const std::vector<PreparedVolume>& bodies,
                 double near, double far);

}  // namespace kccd::render::detail
