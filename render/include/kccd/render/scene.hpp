// From a model and a query to the volumes the renderer draws.
#pragma once

#include <span>
#include <vector>

#include "kccd/checker.hpp"
#include "kccd/render/renderer.hpp"

namespace kccd::render {

/// Per body the smallest distance bound among its pairs in a query result (+inf in none).
std::vector<double> bodyDistances(const Model& model, const QueryResult& result);

/// Per body status from a Distances query result: the smallest bound among the body's pairs,
/// <= 0 colliding, <= margin within margin, else clear. An unsafe query status (anything but
/// Ok) makes every body colliding. Bodies in no checked pair are clear.
std::vector<SafetyStatus> bodyStatus(const Model& model, const QueryResult& result);

/// The volumes of every body for the checker's last query box, in world coordinates and model
/// order (static volumes when lower == upper, swept volumes otherwise). `status` may be empty:
/// every body is then grey (no state). The views point into the checker (valid until its next query).
std::vector<Volume> sceneVolumes(const Model& model, Checker& checker, const std::vector<SafetyStatus>& status);

/// The static volumes at one configuration `state` (the checker's last query must be that point
/// state). A body moved rigidly is drawn as it is, whatever the model's point budget: its own
/// points (radius + 1 nm, covering the checker's rounding guard) with its frame's pose, so its
/// mesh stays cached while the robot moves; a body below a joint with an error bound (which
/// grows its volume) takes the checker's world volume. The point views refer to the model and the checker.
std::vector<Volume> staticSceneVolumes(const Model& model, Checker& checker, std::span<const double> state,
                                       const std::vector<SafetyStatus>& status);

}  // namespace kccd::render
