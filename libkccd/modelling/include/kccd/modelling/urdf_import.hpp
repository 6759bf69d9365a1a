// URDF (and SRDF) to a KCCD model: joints and origins mapped one to one, each link's collision
// geometry fitted with a conservative SSCH.
#pragma once

#include <functional>
#include <map>
#include <string>

#include "kccd/input_error.hpp"
#include "kccd/modelling/fit_request.hpp"

namespace kccd::modelling {

/// A URDF or SRDF file that cannot be imported: one line naming the file, line and element.
class UrdfError : public InputError {
 public:
  using InputError::InputError;
};

/// How a URDF is imported (kccd import's defaults; docs/guides/import-robot.md says why).
struct ImportOptions {
  std::string srdf;  ///< optional SRDF: disable_collisions -> ignore
  /// How each link (each piece of a concave one) is fitted: by default within 2 mm of its hull,
  /// concave links in up to 8 pieces. FitMethod::Hull: the links' convex hulls, a tight, slow
  /// reference to measure what a fit costs.
  FitRequest fit{.method = FitMethod::Tolerance, .max_pieces = kAutoPieces};
  double safety_margin = 0.02;                  ///< written into the model
  std::map<std::string, std::string> packages;  ///< package:// NAME -> directory
  bool visuals = true;                          ///< write each link's <visual>s as `visuals:` (meshes must exist)
  bool keep_adjacent = false;                   ///< check adjacent links (else ignored: Connection::Adjacent)
  std::function<void(double)> progress;
};

/// Converts the URDF file at `path` into `kccd: 1` model text (checked by loading it back).
/// Each link with collision geometry becomes one body, or with fit.max_pieces > 1 and a concavity
/// above fit.concavity (splitConcave) the bodies LINK/1, LINK/2, ... (`link: LINK`, in the link's
/// frame); every body records the bound it meets as `tolerance:` (FitResult::outside).
/// `pairs: ignore` lists, each with its reason, the links joined only by fixed joints (rigid),
/// those joined by one moving joint with no link with geometry between them (adjacent, unless
/// keep_adjacent), then the SRDF's disable_collisions (srdf).
/// Joints map one to one, except: a floating joint J becomes J (translation3d) and J_rotation
/// (rotation3d); a planar joint J becomes J_x and J_y (prismatic along two axes of the plane
/// normal to its axis) and J_yaw (revolute about that axis). Throws UrdfError with one line
/// naming the file and the element on any problem: unreadable XML, unresolved or unreadable
/// meshes, a chain joint's name taken by another joint; FitRequestError for a request out of range.
std::string importUrdf(const std::string& path, const ImportOptions& options = {});

}  // namespace kccd::modelling
