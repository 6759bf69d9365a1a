// URDF (and SRDF) to a KCCD model: joints and origins mapped one to one, each link's collision
// geometry fitted with a conservative SSCH.
#pragma once

#include <functional>
#include <map>
#include <string>

#include "kccd/input_error.hpp"

namespace kccd::modelling {

/// A URDF or SRDF file that cannot be imported: one line naming the file, line and element.
class UrdfError : public InputError {
 public:
  using InputError::InputError;
};

/// kccd import's defaults: the tolerance each link's volume meets (mm outside its hull) and the
/// concavity above which a link splits into pieces (mm); docs/guides/import-robot.md says why.
inline constexpr double kDefaultToleranceMm = 2.0;
inline constexpr double kDefaultConcavityMm = 40.0;

struct ImportOptions {
  std::string srdf;                             ///< optional SRDF: disable_collisions -> ignore
  int points = 8;                               ///< core points per fitted link (1 ... 16); with tolerance
                                                ///< > 0 the fit tried first (fitToTolerance)
  double tolerance = kDefaultToleranceMm * 1e-3;  ///< metres each volume may reach outside its link's hull;
                                                ///< 0: a fixed K = points fit
  int max_pieces = 8;                           ///< a concave link splits into at most this many pieces
  double concavity = kDefaultConcavityMm * 1e-3;  ///< a link (piece) splits while its concavity exceeds this (metres)
  double safety_margin = 0.02;                  ///< written into the model
  std::map<std::string, std::string> packages;  ///< package:// NAME -> directory
  bool visuals = true;                          ///< write each link's <visual>s as `visuals:` (meshes must exist)
  bool hulls = false;                           ///< bodies are the links' convex hulls (vertices, no fit): a
                                                ///< tight, slow reference to measure what a fit costs
  bool keep_adjacent = false;                   ///< check adjacent links (else ignored: Connection::Adjacent)
  std::function<void(double)> progress;
};

/// Converts the URDF file at `path` into `kccd: 1` model text (checked by loading it back).
/// Each link with collision geometry becomes one body, or with max_pieces > 1 and a concavity
/// above `concavity` (splitConcave) the bodies LINK/1, LINK/2, ... (`link: LINK`, in the link's
/// frame); every body records the bound it meets as `tolerance:` (FitResult::outside).
/// `pairs: ignore` lists, each with its reason, the links joined only by fixed joints (rigid),
/// those joined by one moving joint with no link with geometry between them (adjacent, unless
/// keep_adjacent), then the SRDF's disable_collisions (srdf).
/// Joints map one to one, except: a floating joint J becomes J (translation3d) and J_rotation
/// (rotation3d); a planar joint J becomes J_x and J_y (prismatic along two axes of the plane
/// normal to its axis) and J_yaw (revolute about that axis). Throws UrdfError with one line
/// naming the file and the element on any problem: unreadable XML, unresolved or unreadable
/// meshes, a chain joint's name taken by another joint.
std::string importUrdf(const std::string& path, const ImportOptions& options = {});

}  // namespace kccd::modelling
