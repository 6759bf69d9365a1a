// A run's timeline: what an operator reads first about a long recording. The smallest distance
// bound over the frames' times with the safety margin, the spans within the margin, colliding,
// unsafe or without a state shaded, the link pairs responsible for each span named, and the
// contact sheet's frames marked; with robot masks, each frame's agreement with them below.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/recording/overlay_recording.hpp"

namespace kccd::overlay {

/// Draws the timeline of `report` (its frames, margin and contact-sheet frames; the pairs named by
/// `model`'s link names) as a BGR picture `width` pixels wide (480 ... 8192), captioned `title`.
/// The distance axis shows 0 to a round value above the margin and most bounds; bounds above it sit
/// on the top edge. The spans are listed below the plot, the most severe first (at most 12, then a
/// count of the rest). Throws InputError for a width out of range or a report without frames.
cv::Mat drawTimeline(const OverlayReport& report, const Model& model, const std::string& title, int width = 1600);

}  // namespace kccd::overlay
