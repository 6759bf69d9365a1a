// The candidate points of a frame for hand labelling, as data: the AprilTags detected in it, strong
// image corners, and the model's core points projected by a camera with a rough pose. What a
// labelling page shows and `kccd calib sheet` draws, and the labels file to fill in from them.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/calib/tag_layout.hpp"
#include "kccd/model.hpp"

namespace kccd::overlay {

/// A detected tag.
struct TagCandidate {
  int id = 0;
  std::array<cv::Point2d, 4> corners;  ///< AprilTag's corner order (calib::TagDetection), OpenCV pixels
  bool placed = false;                 ///< the tag layout places it (calibration takes its corners itself)
};

/// A strong image corner.
struct CornerCandidate {
  std::string name;   ///< "p1", "p2", ... strongest first
  cv::Point2d pixel;  ///< sub-pixel, OpenCV pixels
};

/// A core point of the model where the camera projects it.
struct ModelPointCandidate {
  std::string name;          ///< "<body name>.<k>"
  std::string body;          ///< the body's name
  int point = 0;             ///< k: index into the body's points
  Vec3 body_point;           ///< the point in the body's frame
  bool world_fixed = false;  ///< the body is fixed in the world: its points are world points
  cv::Point3d world;         ///< the point in the world at the state
  cv::Point2d pixel;         ///< where the camera projects it
};

/// Every candidate of one frame.
struct LabellingCandidates {
  std::vector<TagCandidate> tags;                 ///< in the detector's order
  std::vector<CornerCandidate> corners;           ///< none inside or near a tag
  std::vector<ModelPointCandidate> model_points;  ///< in front of the camera and inside the image, model order
  std::vector<double> state;                      ///< the state the model's points are placed at
  bool layout = false;                            ///< a tag layout said which tags are placed
};

/// What to look for in a frame.
struct CandidateInputs {
  std::string image;                     ///< names the frame in messages
  std::optional<calib::TagLayout> tags;  ///< marks the tags it places (a tag detected twice is an error)
  int corners = 40;                      ///< most strong corners offered
  std::optional<calib::Camera> camera;   ///< with a rough pose; the frame must have its size
  std::string camera_name;               ///< names the camera in messages
  const Model* model = nullptr;          ///< its core points are projected (needs `camera`)
  std::vector<double> state;             ///< the model's state in the frame (the model's state size)
};

/// The candidates of `bgr` (8-bit BGR). Throws CalibInputError (the frame does not fit the camera,
/// a model without a camera or with a state of the wrong size) or calib::TagDetectionError.
LabellingCandidates labellingCandidates(const cv::Mat& bgr, const CandidateInputs& inputs);

/// Strong, well separated corners of a grey image (sub-pixel), at most `count`, strongest first,
/// none inside or within a few pixels of a detected tag (tag corners are offered by the tags).
std::vector<cv::Point2d> strongCorners(const cv::Mat& gray, const std::vector<calib::TagDetection>& tags, int count);

/// A labels file to fill in (docs/formats.md section 5), every candidate commented out: strong
/// corners and the corners of tags the layout does not place with a world point to give, model
/// points as body points at the state (world points for fixed bodies). `image` and `sheet` name
/// the frame and the sheet image in its header.
std::string labelsTemplate(const LabellingCandidates& candidates, const std::string& image, const std::string& sheet);

}  // namespace kccd::overlay
