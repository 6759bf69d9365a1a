// The status line of an overlaid frame: what it says of the frame, field by field, and how it is
// shortened to fit the frame's width.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <opencv2/core/types.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/recording/frame_annotator.hpp"

namespace kccd::overlay {

/// One part of the status line, e.g. "min distance 0.0179 m".
struct StatusField {
  std::string text;
  int rank = 0;                  ///< importance: 0 first, the highest rank the first to go when the line is too long
  std::string separator = "  ";  ///< what joins it to the field before it
  std::size_t cut_keeping = 0;   ///< > 0: may be cut at a word boundary, keeping at least this many words
  bool with_previous = false;    ///< shown only when the field before it is (e.g. "(exact)" after the time)
};

/// What the status line says of `record`, in order: the log time, how the state was found and
/// "swept", then the smallest distance bound and the pairs within the margin, or NO STATE and why,
/// or UNSAFE and why. The verdict (distance, NO STATE, UNSAFE) has rank 0.
std::vector<StatusField> statusFields(const FrameRecord& record, const Model& model, const AnnotatorSettings& settings);

/// The fields in their order, as many as fit `width(text) <= max_width`: taken by rank (the earlier
/// of equals first), each one kept if the line still fits, else cut at a word boundary with " ..."
/// if it may be and some of its words fit, else left out. The most important field may always be
/// cut (keeping one word). Never cut inside a word; empty when not even one word fits.
std::string fitStatus(std::vector<StatusField> fields, int max_width,
                      const std::function<int(const std::string&)>& width);

/// The colour of a frame's status line (BGR): white when clear, else the status's colour.
cv::Scalar statusTextColour(SafetyStatus status);

}  // namespace kccd::overlay
