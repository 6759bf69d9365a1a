// From a model and a query to the volumes the renderer draws.
#pragma once

#include <vector>

#include "kccd/checker.hpp"
#include "kccd/render/renderer.hpp"

namespace kccd::render {

/// Per body status from a Distances query result: the smallest bound among the body's pairs,
/// <= 0 colliding, <= margin within margin, else clear. An unsafe query status (anything but
/// Ok) makes every body colliding. Bodies in no checked pair are clear.
std::vector<VolumeStatus> bodyStatus(const Model& model, const QueryResult& result);

/// The volumes of every body for the checker's last query box, in world coordinates and model
/// order (static volumes when lower == upper, swept volumes otherwise). `status` may be empty:
/// every body is then grey (no state). The views point into the checker (valid until its next query).
std::vector<Volume> sceneVolumes(const Model& model, Checker& checker, const std::vector<VolumeStatus>& status);

}  // namespace kccd::render
