#include "kccd/overlay/recording/frame_annotator.hpp"

#include <algorithm>
#include <chrono>
#include <string>

#include <opencv2/core.hpp>

namespace kccd::overlay {

std::vector<std::array<std::string, 2>> linkPairs(const Model& model, const std::vector<std::array<int, 2>>& pairs) {
  std::vector<std::array<std::string, 2>> out;
  for (const auto& p : pairs) {
    const std::array<std::string, 2> l{model.bodies[p[0]].linkName(), model.bodies[p[1]].linkName()};
    if (std::find(out.begin(), out.end(), l) == out.end()) out.push_back(l);
  }
  return out;
}

StageTimes& StageTimes::operator+=(const StageTimes& o) {
  decode += o.decode, state += o.state, query += o.query, render += o.render;
  read_back += o.read_back, warp += o.warp, composite += o.composite, encode += o.encode;
  return *this;
}

const char* FrameRecord::queryStatusText() const {
  return braking_failed ? "no_braking_box" : not_finite ? "volume_not_finite" : toString(query);
}

FrameAnnotator::FrameAnnotator(const AnnotatorScene& scene)
    : scene_(scene),
      view_(scene.model, scene.projection, scene.render_options,
            std::vector<render::LoadedVisual>(scene.visuals.begin(), scene.visuals.end())),
      q_(scene.model.stateSize()),
      v_(scene.model.stateSize()),
      lo_(scene.model.stateSize()),
      hi_(scene.model.stateSize()),
      all_colliding_(scene.model.bodies.size(), SafetyStatus::Colliding) {}

FrameAnnotator::~FrameAnnotator() = default;

void recordAnswer(const Model& m, const QueryResult& r, bool box_ok, FrameRecord& rec, bool pairs) {
  rec.query = r.status;
  // A bound only for the box the run is about: none for an unsafe status or a missing braking box.
  if (r.status == Status::Ok && box_ok) rec.min_distance = r.min_distance;
  if (pairs)
    for (const PairDistance& pd : r.pairs)
      if (pd.distance <= r.margin) rec.pairs.push_back({m.pairs[pd.pair].a, m.pairs[pd.pair].b});
  rec.status = box_ok ? safetyStatus(r) : SafetyStatus::Colliding;
}

void FrameAnnotator::annotate(cv::Mat& bgr, FrameRecord& rec) {
  const Model& m = scene_.model;
  const AnnotatorSettings& set = scene_.settings;
  using Clock = std::chrono::steady_clock;
  const auto since = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  const Clock::time_point t_state = Clock::now();
  const double t = rec.time + set.time_offset;
  rec.match = set.swept ? stateAt(scene_.log, t, set.max_gap, q_, v_) : stateAt(scene_.log, t, set.max_gap, q_);
  render::ModelViewRequest request;
  request.tight_volumes = true;
  request.visuals = true;  // when the scene has visuals and a state is known: the robot's look at it
  request.mask = false;
  request.colour = rec.selected;  // not selected: the query alone
  request.style.labels = false;
  request.style.legend = false;  // the legend and the status line are drawn by FrameDecoration
  request.onto = &bgr;           // the layer composited in the warp's pass
  bool box_ok = true;
  if (rec.match == StateMatch::None) {
    // No state: only the bodies fixed in the world are known; they are drawn grey.
    rec.status = SafetyStatus::NoState;
    if (!rec.selected) return;
  } else {
    rec.values.assign(q_.begin(), q_.end());
    request.state = q_;
    if (set.swept) {
      box_ok = brakingIntervals(m, q_, v_, set.braking, lo_, hi_);
      if (box_ok) {
        request.lower = lo_;
        request.upper = hi_;
      } else {
        // No braking box: the static volumes at the state, all coloured colliding.
        rec.braking_failed = true;
        request.status = all_colliding_;
      }
    }
  }
  rec.times.state = since(t_state);
  under_legend_.resize(set.legend_corners.size());
  if (rec.selected)
    for (std::size_t i = 0; i < set.legend_corners.size(); ++i) bgr(set.legend_corners[i]).copyTo(under_legend_[i]);
  // The view queries from scratch every frame: the answer does not depend on which annotator had which frame.
  const render::ModelFrame drawn = view_.draw(request);
  const render::FrameTimes& ft = drawn.images.times;
  rec.times.query = drawn.query_seconds;
  rec.reused = drawn.reused;
  rec.times.render = ft.prepare + ft.draw;
  rec.times.read_back = ft.read_back;
  rec.times.warp = ft.warp + ft.decorate;
  if (drawn.query) recordAnswer(m, *drawn.query, box_ok, rec);
  if (!rec.selected) return;
  const render::Frame& layer = drawn.images;
  for (std::size_t i = 0; i < drawn.first_visual; ++i)
    rec.not_finite |= layer.visibility[i] == render::Visibility::NotFinite;
  if (rec.not_finite) rec.status = SafetyStatus::Colliding;  // an overflowed volume is unsafe
  // The pixels the volumes changed under each legend corner: the one changed least hides least.
  for (std::size_t i = 0; i < set.legend_corners.size() && i < rec.legend_cover.size(); ++i) {
    const cv::Mat now = bgr(set.legend_corners[i]);
    cv::absdiff(now, under_legend_[i], difference_);
    cv::inRange(difference_, cv::Scalar::all(0), cv::Scalar::all(0), unchanged_);
    rec.legend_cover[i] = static_cast<int>(now.total()) - cv::countNonZero(unchanged_);
  }
}

}  // namespace kccd::overlay
