// What an overlaid frame shows besides the volumes: the status line and the legend, sized for the
// frame (render::textMetrics), the legend in a corner of the picture or in a strip under it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/model.hpp"
#include "kccd/overlay/recording/frame_annotator.hpp"
#include "kccd/render/text_metrics.hpp"

namespace kccd::overlay {

/// Where the legend goes (kccd overlay --legend).
enum class LegendPlace { Auto, TopLeft, TopRight, BottomLeft, BottomRight, Outside, Off };

/// The place a word names: "auto", "top-left", "top-right", "bottom-left", "bottom-right", "outside" or "off".
std::optional<LegendPlace> legendPlaceOf(const std::string& word);

/// The words legendPlaceOf takes, quoted, for messages ("'auto', 'outside', ... or 'bottom-right'").
std::string legendPlaceWords();

/// Where the status line and the legend go on the frames of one run, and their drawing.
class FrameDecoration {
 public:
  /// For pictures of `picture`'s size, with a status line unless `status_line` is false. A legend
  /// that does not fit the picture (or its width, outside) is scaled down to fit; on a picture
  /// too small for even that, none is drawn.
  FrameDecoration(cv::Size picture, LegendPlace place, bool status_line);

  /// The frames handed on: the picture's size, with Outside taller by the strip under it (its
  /// height keeps the picture's height's parity).
  cv::Size frameSize() const { return frame_; }
  /// The legend's candidate boxes on the picture, above the status line: top-left, top-right,
  /// bottom-left, bottom-right, or the one corner asked for; none with Outside or Off.
  const std::vector<cv::Rect>& corners() const { return corners_; }
  /// The text's size and spacing on these frames.
  const render::TextMetrics& text() const { return text_; }
  /// Whether a status line is drawn.
  bool statusLine() const { return status_line_; }
  /// The widest status line that fits (pixels of text).
  int statusWidth() const;
  /// The box the status line `status` takes on the frame (empty for an empty line).
  cv::Rect statusBox(const std::string& status) const;

  /// Draws onto `frame` (frameSize(), CV_8UC3, the picture at its top): `status` in `colour` (none
  /// when empty) on a darkened box at the bottom left, or in the strip; the legend in box
  /// corners()[corner], or in the strip.
  void draw(cv::Mat& frame, const std::string& status, const cv::Scalar& colour, int corner = 0) const;

 private:
  cv::Size picture_, frame_;
  render::TextMetrics text_;
  bool status_line_ = true, outside_ = false;
  cv::Mat legend_;  // BGRA, straight alpha; empty: none
  std::vector<cv::Rect> corners_;
  cv::Point strip_legend_;  // the legend's top-left in the strip
};

/// `picture` (CV_8UC3, the volumes drawn) as handed on for `record`: the status line of
/// statusFields shortened by fitStatus to statusWidth(), and the legend in corners()[corner],
/// drawn by `decoration`. Returns `picture` itself, or with Outside `tall` holding the picture and the strip.
cv::Mat& decorateFrame(cv::Mat& picture, cv::Mat& tall, const FrameDecoration& decoration, const FrameRecord& record,
                       const Model& model, const AnnotatorSettings& settings, int corner);

}  // namespace kccd::overlay
