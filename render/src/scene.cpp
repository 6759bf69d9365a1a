#include "kccd/render/scene.hpp"

#include <limits>

namespace kccd::render {

std::vector<VolumeStatus> bodyStatus(const Model& model, const QueryResult& result) {
  std::vector<VolumeStatus> out(model.bodies.size(), VolumeStatus::Clear);
  if (result.status != Status::Ok) {
    out.assign(model.bodies.size(), VolumeStatus::Colliding);
    return out;
  }
  std::vector<double> nearest(model.bodies.size(), std::numeric_limits<double>::infinity());
  for (const PairDistance& pd : result.pairs) {
    const BodyPair& p = model.pairs[pd.pair];
    nearest[p.a] = std::min(nearest[p.a], pd.distance);
    nearest[p.b] = std::min(nearest[p.b], pd.distance);
  }
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (nearest[i] <= 0.0)
      out[i] = VolumeStatus::Colliding;
    else if (nearest[i] <= result.margin)
      out[i] = VolumeStatus::WithinMargin;
  }
  return out;
}

std::vector<Volume> sceneVolumes(const Model& model, Checker& checker, const std::vector<VolumeStatus>& status) {
  std::vector<Volume> out;
  out.reserve(model.bodies.size());
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const SschView v = checker.sweptVolume(static_cast<int>(i), kWorld);
    out.push_back(Volume{v.points, v.radius, status.empty() ? VolumeStatus::NoState : status[i], model.bodies[i].name});
  }
  return out;
}

}  // namespace kccd::render
