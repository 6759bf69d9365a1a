#include "kccd/render/model_view.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "kccd/kinematics.hpp"
#include "kccd/render/scene.hpp"

namespace kccd::render {

int cameraFrame(const Model& model, const Camera& camera, const std::string& source) {
  if (camera.frame.empty() || camera.frame == "world") return kWorld;
  if (const int j = model.jointIndex(camera.frame); j >= 0) return j;
  for (const Body& b : model.bodies)
    if (b.name == camera.frame || b.linkName() == camera.frame) return b.frame;
  throw CameraError(InputLocation{source, 0, 0, "frame"}, "'" + printable(camera.frame, 60) +
                                                              "' is neither a joint nor a body or link of " +
                                                              model.name + " (the frame the camera is fixed to)");
}

ModelView::ModelView(const Model& model, const Camera& camera, const RenderOptions& options,
                     std::vector<LoadedVisual> visuals)
    : model_(model),
      checker_(model),
      renderer_(camera, options),
      visuals_(std::move(visuals)),
      camera_frame_(cameraFrame(model, camera)) {}

ModelView::ModelView(const Model& model, const Projection& projection, const RenderOptions& options,
                     std::vector<LoadedVisual> visuals)
    : model_(model),
      checker_(model),
      renderer_(projection, options),
      visuals_(std::move(visuals)),
      camera_frame_(cameraFrame(model, projection.camera())) {}

bool ModelView::sameAsLastOnto(const ModelViewRequest& r) const {
  if (!last_onto_ || r.onto == nullptr || !r.colour || r.mask) return false;
  const LastOnto& l = *last_onto_;
  // Bit for bit: == on doubles (a NaN is never equal, so never reused).
  return std::ranges::equal(r.state, l.state) && std::ranges::equal(r.lower, l.lower) &&
         std::ranges::equal(r.upper, l.upper) && std::ranges::equal(r.status, l.status) &&
         std::ranges::equal(r.colours, l.colours) && r.radius_scale == l.radius_scale &&
         r.tight_volumes == l.tight_volumes && r.volumes == l.volumes && r.visuals == l.visuals && r.style == l.style &&
         renderer_.canRenderOntoAgain(r.style);
}

ModelFrame ModelView::draw(const ModelViewRequest& request) {
  if (sameAsLastOnto(request)) {
    ModelFrame out = last_onto_->frame;
    out.images = renderer_.renderOntoAgain(*request.onto, request.style);
    out.query_seconds = 0.0;
    out.reused = true;
    return out;
  }
  last_onto_.reset();  // the checker and the renderer move on
  ModelFrame out = drawAnew(request);
  if (request.onto != nullptr && request.colour && !request.mask && renderer_.canRenderOntoAgain(request.style)) {
    const ModelViewRequest& r = request;
    last_onto_ = LastOnto{{r.state.begin(), r.state.end()},
                          {r.lower.begin(), r.lower.end()},
                          {r.upper.begin(), r.upper.end()},
                          {r.status.begin(), r.status.end()},
                          {r.colours.begin(), r.colours.end()},
                          r.radius_scale,
                          r.tight_volumes,
                          r.volumes,
                          r.visuals,
                          r.style,
                          out};
  }
  return out;
}

bool ModelView::placeInCameraFrame(const ModelViewRequest& request, std::vector<Volume>& volumes) const {
  // The renderer's world is the camera's frame: every volume is moved from the world into it, at
  // the state (or the box's middle) the frame is at.
  std::vector<double> at(request.state.begin(), request.state.end());
  if (at.empty())
    for (std::size_t i = 0; i < request.lower.size() && i < request.upper.size(); ++i)
      at.push_back(0.5 * (request.lower[i] + request.upper[i]));
  std::vector<Pose> poses(model_.joints.size());
  if (at.empty() || !framePoses(model_, at, poses)) return false;
  const Pose to_frame = framePose(poses, camera_frame_).inverse();
  for (Volume& v : volumes) v.pose = to_frame * v.pose;
  return true;
}

ModelFrame ModelView::drawAnew(const ModelViewRequest& request) {
  const std::size_t n = model_.bodies.size();
  if (!request.status.empty() && request.status.size() != n)
    throw std::invalid_argument("ModelView: " + std::to_string(request.status.size()) + " statuses for " +
                                std::to_string(n) + " bodies");
  if (!request.colours.empty() && request.colours.size() != n)
    throw std::invalid_argument("ModelView: " + std::to_string(request.colours.size()) + " colours for " +
                                std::to_string(n) + " bodies");
  ModelFrame out;
  const bool drawn = request.colour || request.mask;  // else the query and the statuses alone
  std::vector<Volume> volumes;
  const bool box = !request.lower.empty() || !request.upper.empty();
  if (request.state.empty() && !box) {
    // No state: only the bodies fixed in the world are known; they are drawn grey.
    out.status.assign(n, SafetyStatus::NoState);
    if (request.volumes && drawn) {
      volumes.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        const Body& b = model_.bodies[i];
        volumes[i].label = b.name;
        if (b.frame != kWorld) continue;  // not drawn: no volume
        volumes[i].points = b.points;
        volumes[i].radius = b.radius * (1.0 + 1e-9) + 1e-9;  // as staticSceneVolumes draws a body moved rigidly
      }
    }
  } else {
    // From scratch every time: the answer does not depend on what this view drew before.
    const auto t0 = std::chrono::steady_clock::now();
    checker_.reset();
    const QueryResult& r =
        box ? checker_.query(request.lower, request.upper,
                             QueryOptions{.type = QueryType::Distances, .tight_volumes = request.tight_volumes})
            : checker_.query(request.state, request.state,
                             QueryOptions{.type = QueryType::Distances, .tight_volumes = request.tight_volumes});
    out.query = r;
    out.distances = bodyDistances(model_, r);
    out.status = request.status.empty() ? bodyStatus(model_, r)
                                        : std::vector<SafetyStatus>(request.status.begin(), request.status.end());
    if (request.volumes && drawn)
      volumes = box ? sceneVolumes(model_, checker_, out.status)
                    : staticSceneVolumes(model_, checker_, request.state, out.status);
    out.query_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  if (!drawn) return out;
  if (camera_frame_ != kWorld && !placeInCameraFrame(request, volumes)) volumes.clear();
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    if (request.radius_scale != 1.0) volumes[i].radius *= request.radius_scale;
    if (!request.colours.empty()) volumes[i].colour = request.colours[i];
  }
  out.first_visual = volumes.size();
  if (request.visuals && !request.state.empty() && !visuals_.empty()) {
    std::vector<Volume> look = visualVolumes(model_, visuals_, request.state);
    if (camera_frame_ != kWorld && !placeInCameraFrame(request, look)) look.clear();
    volumes.insert(volumes.end(), std::make_move_iterator(look.begin()), std::make_move_iterator(look.end()));
  }
  out.images = request.onto && request.colour && !request.mask
                   ? renderer_.renderOnto(*request.onto, volumes, request.style)
                   : renderer_.render(volumes, request.style, request.colour, request.mask);
  return out;
}

}  // namespace kccd::render
