// The colour legend of the safety statuses (clear, within margin, colliding, no state) as an image
// to put onto a camera frame.
#pragma once

#include <opencv2/core.hpp>

#include "kccd/render/text_metrics.hpp"

namespace kccd::render {

/// The legend at `text`'s size in `columns` columns (1: a status a line, as in a corner; 2; 4: one
/// row, as in a strip under a frame): per status a swatch in statusColour and its name, white
/// outlined in black, on a dark translucent box that fills the image. CV_8UC4, straight alpha.
cv::Mat statusLegend(const TextMetrics& text, int columns = 1);

}  // namespace kccd::render
