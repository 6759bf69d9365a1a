// The camera pose refined so that the robot's outline, drawn from the model at each frame's state
// (silhouette.hpp), lies on the pictures' own edges, over all frames together: calibration from
// the image alone where no robot mask is at hand. The intrinsics and lens stay as they are.
#pragma once

#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/calib/camera.hpp"
#include "kccd/calib/correspondence.hpp"
#include "kccd/calib/mask_refine.hpp"
#include "kccd/calib/silhouette.hpp"

namespace kccd::calib {

/// One frame to fit: its picture and the model's volumes placed at its state.
struct EdgeFrame {
  cv::Mat image;                      ///< 8-bit grey or BGR, the camera's size
  std::vector<PlacedVolume> volumes;  ///< world coordinates
  /// What the robot looks like (visual meshes): drawn instead of the volumes at full resolution
  /// when given (the coarse stages draw the volumes: give those of the bodies the meshes show).
  std::vector<PlacedMesh> meshes;
};

/// How the edge refinement runs.
struct EdgeOptions {
  double spacing_px = 2.0;    ///< outline samples' spacing
  int max_iterations = 30;    ///< per stage
  double match_px = 2.0;      ///< an outline point within this of an edge of its direction is "on an edge"
  double min_matched = 0.35;  ///< a refined pose with less of its outline on edges (mean over frames) is not a camera
  /// nor one the edges pin down less well than this (measured when right: 0.02-0.11 deg on 4-6
  /// synthetic pictures, 0.07 deg on 10 real photos of 1280x720, 0.17 on 3 of them; when wrong:
  /// 0.37 deg for pictures of other states whose clutter happened to line up, 1.1 deg on 1 photo)
  double max_rotation_sigma_deg = 0.25;
  double click_px = 8.0;  ///< how far off the clicks may be (their robust loss's scale)
  /// As RefineOptions::start_is_prior: a pose beyond 3 sigma of the start's for a gain in the
  /// matched share below 0.05 keeps the start.
  bool start_is_prior = false;
};

/// Refines `start`'s pose so the drawn outlines lie on the pictures' edges. Each picture's edges
/// (Canny, thresholds from its own gradient statistics) are found on a pyramid of three levels;
/// from each drawn outline point the nearest edge whose direction is within 30 degrees of the
/// outline's is searched along the outline's normal, and the point is pulled onto it (point to
/// line) by the robust fit of the masks (a Cauchy loss whose scale shrinks from coarse to fine).
/// Clutter is rejected by direction (an edge across the outline does not count), by scale (the
/// coarse levels hold only large structures: a second arm or a shadow far from the drawn robot
/// is beyond the shrinking search), and by the robust loss (points whose nearest edge is far off
/// count little). The result is kept only if the mean matched share grows and no frame's falls by
/// more than 0.05, with at least min_matched on edges and a rotation sigma within bounds; else
/// the start is returned and the message says why. `clicks` (labelled points, tag corners: what
/// gave the start) hold the fit near them by a robust loss of scale click_px, so a start from a few
/// rough clicks that is some 15 degrees off along the view (the clicks agree, the outline does not)
/// is not pulled into the clutter; the pose's sigmas are the edges' alone. Throws InputError for
/// no frame or a picture of another size than the camera's.
RefineResult refineToEdges(const Camera& start, std::span<const EdgeFrame> frames, const EdgeOptions& options = {},
                           std::span<const Correspondence> clicks = {});

}  // namespace kccd::calib
