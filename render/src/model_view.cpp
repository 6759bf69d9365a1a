#include "kccd/render/model_view.hpp"

#include <algorithm>
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
