#include "kccd/render/scene.hpp"

#include <limits>

#include "kccd/kinematics.hpp"

namespace kccd::render {

std::vector<double> bodyDistances(const Model& model, const QueryResult& result) {
  std::vector<double> nearest(model.bodies.size(), std::numeric_limits<double>::infinity());
  for (const PairDistance& pd : result.pairs) {
    const BodyPair& p = model.pairs[pd.pair];
    nearest[p.a] = std::min(nearest[p.a], pd.distance);
    nearest[p.b] = std::min(nearest[p.b], pd.distance);
  }
  return nearest;
}

std::vector<SafetyStatus> bodyStatus(const Model& model, const QueryResult& result) {
  std::vector<SafetyStatus> out(model.bodies.size(), SafetyStatus::Clear);
  if (result.status != Status::Ok) {
    out.assign(model.bodies.size(), SafetyStatus::Colliding);
    return out;
  }
  const std::vector<double> nearest = bodyDistances(model, result);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = safetyStatus(nearest[i], result.margin);
  return out;
}

std::vector<Volume> sceneVolumes(const Model& model, Checker& checker, const std::vector<SafetyStatus>& status) {
  std::vector<Volume> out;
  out.reserve(model.bodies.size());
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const SschView v = checker.sweptVolume(static_cast<int>(i), kWorld);
    out.push_back(Volume{v.points, v.radius, status.empty() ? SafetyStatus::NoState : status[i], model.bodies[i].name});
  }
  return out;
}

std::vector<Volume> staticSceneVolumes(const Model& model, Checker& checker, std::span<const double> state,
                                       const std::vector<SafetyStatus>& status) {
  std::vector<Volume> out = sceneVolumes(model, checker, status);
  std::vector<Pose> poses(model.joints.size());
  if (!framePoses(model, state, poses)) return out;  // the checker's (unsafe) volumes as they are
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Body& b = model.bodies[i];
    // A body moved rigidly is drawn as it is: its own points and radius, whatever the point
    // budget (the checker may hold a reduced stand-in with a larger radius: an engine detail).
    // The drawn radius takes 1 nm more than the body's, covering the checker's rounding guard,
    // fixed per body so that its mesh stays cached. A body below a joint with an error bound
    // keeps the checker's grown volume.
    const double drawn = b.radius * (1.0 + 1e-9) + 1e-9;
    if (hasErrorBound(model, b.frame)) continue;
    out[i].points = b.points;
    out[i].radius = drawn;
    out[i].pose = framePose(poses, b.frame);
  }
  return out;
}

}  // namespace kccd::render
