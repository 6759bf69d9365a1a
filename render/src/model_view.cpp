#include "kccd/render/model_view.hpp"

#include <chrono>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "kccd/render/scene.hpp"

namespace kccd::render {

ModelView::ModelView(const Model& model, const Camera& camera, const RenderOptions& options,
                     std::vector<LoadedVisual> visuals)
    : model_(model), checker_(model), renderer_(camera, options), visuals_(std::move(visuals)) {}

ModelView::ModelView(const Model& model, const Projection& projection, const RenderOptions& options,
                     std::vector<LoadedVisual> visuals)
    : model_(model), checker_(model), renderer_(projection, options), visuals_(std::move(visuals)) {}

ModelFrame ModelView::draw(const ModelViewRequest& request) {
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
  for (std::size_t i = 0; i < volumes.size(); ++i) {
    if (request.radius_scale != 1.0) volumes[i].radius *= request.radius_scale;
    if (!request.colours.empty()) volumes[i].colour = request.colours[i];
  }
  out.first_visual = volumes.size();
  if (request.visuals && !request.state.empty() && !visuals_.empty()) {
    std::vector<Volume> look = visualVolumes(model_, visuals_, request.state);
    volumes.insert(volumes.end(), std::make_move_iterator(look.begin()), std::make_move_iterator(look.end()));
  }
  out.images = request.onto && request.colour && !request.mask
                   ? renderer_.renderOnto(*request.onto, volumes, request.style)
                   : renderer_.render(volumes, request.style, request.colour, request.mask);
  return out;
}

}  // namespace kccd::render
