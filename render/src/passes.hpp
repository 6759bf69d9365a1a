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

/// The colour layer of the pinhole image (CV_8UC4, BGRA, premultiplied alpha) through
/// `projection`, between frame.near and frame.far; counts polygon fills into `frame`. With
/// `labels` (and no multisampling, not shaded) the mask labels are drawn in the same pass, just
/// before the colour, and read into *labels.
cv::Mat drawColour(GlTargets& gl, const Projection& projection, const RenderOptions& options,
                   const std::vector<PreparedVolume>& bodies, const Style& style, Frame& frame, cv::Mat* labels = nullptr);

/// The labels alone (a mask without the colour layer, or with the shaded look or multisampling)
/// through the mask pass's projection (CV_8UC1, the pinhole image): the label attachment of the
/// colour target, or the mask's own target at its own scale.
cv::Mat drawMask(GlTargets& gl, const Projection& mask_projection, const std::vector<PreparedVolume>& bodies,
                 double near, double far);

}  // namespace kccd::render::detail
