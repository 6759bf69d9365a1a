// AprilTag (tag36h11) detection in a grey image and the pixel <-> world correspondences the
// detected corners give with a tag layout.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/correspondence.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/input_error.hpp"

namespace kccd::calib {

/// Detections that cannot be used with a layout (a tag id seen twice): one line
/// "image: tags: problem".
class TagDetectionError : public InputError {
 public:
  using InputError::InputError;
};

/// One detected tag.
struct TagDetection {
  int id = 0;
  /// Corners in AprilTag's detection order p[0..3] (counter-clockwise around the tag as seen in
  /// the image, p[0] at the tag frame's (-s/2, -s/2)), in OpenCV's pixel convention (pixel
  /// centres at integers: AprilTag's coordinates minus 0.5).
  std::array<cv::Point2d, 4> corners;
  int hamming = 0;               ///< bits corrected in decoding (0..2)
  double decision_margin = 0.0;  ///< AprilTag's decoding quality
};

/// The fewest pixels across an image can hold a tag in (a tag36h11 tag with its black border is
/// 8 cells across).
inline constexpr int kMinTagPixels = 8;

/// The tag36h11 tags in an 8-bit single-channel image (full resolution, edges refined), in the
/// detector's order; none in an image under kMinTagPixels in either direction. Throws
/// std::invalid_argument for an image that is not CV_8UC1 or is empty.
std::vector<TagDetection> detectTags(const cv::Mat& gray);

/// The correspondences of detected tags that the layout places, and the ids it does not know.
struct TagCorrespondences {
  std::vector<Correspondence>
      points;                    ///< 4 per known tag, in detection then corner order, named "tag3.c0" .. "tag3.c3"
  std::vector<int> unknown_ids;  ///< detected ids not in the layout, ascending, each once
};

/// Pairs every detected corner of a layout tag with its world point (Tag::corners()). A tag id
/// detected twice is a TagDetectionError ("image: tags: tag N is detected twice ..."), `image`
/// naming the image in the message.
TagCorrespondences tagCorrespondences(std::span<const TagDetection> detections, const TagLayout& layout,
                                      const std::string& image);

}  // namespace kccd::calib
