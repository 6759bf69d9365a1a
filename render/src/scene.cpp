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
    // Only where the checker's volume is the body moved rigidly: no error bound, the same points,
    // and a radius grown by no more than rounding (the checker adds a guard of a few ulps; the
    // drawn radius takes 1 nm more, fixed per body so that its mesh stays cached).
    const double drawn = b.radius * (1.0 + 1e-9) + 1e-9;
    if (out[i].points.size() != b.points.size() || hasErrorBound(model, b.frame) || out[i].radius > drawn) continue;
    out[i].points = b.points;
    out[i].radius = drawn;
    out[i].pose = framePose(poses, b.frame);
  }
  return out;
}

}  // namespace kccd::render
