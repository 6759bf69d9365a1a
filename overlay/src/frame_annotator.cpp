#include "kccd/overlay/frame_annotator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <sstream>
#include <string>

#include <opencv2/imgproc.hpp>

#include "kccd/input_error.hpp"
#include "kccd/render/composite.hpp"
#include "kccd/render/scene.hpp"

namespace kccd::overlay {

const char* FrameRecord::queryStatusText() const {
  return braking_failed ? "no_braking_box" : not_finite ? "volume_not_finite" : toString(query);
}

FrameAnnotator::FrameAnnotator(const AnnotatorScene& scene)
    : scene_(scene),
      checker_(scene.model),
      q_(scene.model.stateSize()),
      v_(scene.model.stateSize()),
      lo_(scene.model.stateSize()),
      hi_(scene.model.stateSize()) {
  renderer_ = std::make_unique<render::Renderer>(scene.projection, scene.render_options);
  style_.labels = false;
  style_.legend = !scene.settings.plain;
  for (std::size_t i = 0; i < scene.model.bodies.size(); ++i)
    if (scene.model.bodies[i].frame == kWorld) fixed_.push_back(static_cast<int>(i));
}

FrameAnnotator::~FrameAnnotator() = default;

void FrameAnnotator::annotate(cv::Mat& bgr, FrameRecord& rec) {
  const Model& m = scene_.model;
  const AnnotatorSettings& set = scene_.settings;
  const double t = rec.time + set.time_offset;
  rec.match = set.swept ? stateAt(scene_.log, t, set.max_gap, q_, v_) : stateAt(scene_.log, t, set.max_gap, q_);
  std::vector<render::Volume> volumes;
  if (rec.match == StateMatch::None) {
    rec.status = SafetyStatus::NoState;
    if (!rec.selected) return;
    // No state: only the bodies fixed in the world are known; they are drawn grey.
    for (int i : fixed_) {
      const Body& b = m.bodies[static_cast<std::size_t>(i)];
      volumes.push_back(render::Volume{b.points, b.radius * (1.0 + 1e-9) + 1e-9, SafetyStatus::NoState, b.name});
    }
  } else {
    rec.values.assign(q_.begin(), q_.end());
    bool box_ok = true;
    if (set.swept) {
      box_ok = brakingIntervals(m, q_, v_, set.braking, lo_, hi_);
      if (!box_ok) {
        rec.braking_failed = true;
        lo_ = q_;
        hi_ = q_;
      }
    } else {
      lo_ = q_;
      hi_ = q_;
    }
    // From scratch every frame: the answer does not depend on which annotator had which frame.
    checker_.reset();
    const QueryResult& r = checker_.query(lo_, hi_, QueryOptions{.type = QueryType::Distances, .tight_volumes = true});
    rec.query = r.status;
    // A bound only for the box the run is about: none for an unsafe status or a missing braking box.
    if (r.status == Status::Ok && box_ok) rec.min_distance = r.min_distance;
    for (const PairDistance& pd : r.pairs)
      if (pd.distance <= r.margin) rec.pairs.push_back({m.pairs[pd.pair].a, m.pairs[pd.pair].b});
    rec.status = box_ok ? safetyStatus(r) : SafetyStatus::Colliding;
    if (!rec.selected) return;
    std::vector<SafetyStatus> status = render::bodyStatus(m, r);
    if (!box_ok) status.assign(m.bodies.size(), SafetyStatus::Colliding);
    volumes = set.swept && box_ok ? render::sceneVolumes(m, checker_, status) : render::staticSceneVolumes(m, checker_, q_, status);
  }
  const std::size_t checked = volumes.size();  // the volumes; the visuals come after them
  if (!scene_.visuals.empty() && rec.match != StateMatch::None) {
    // The robot's appearance at the logged state, drawn with the volumes (its own colours).
    std::vector<render::Volume> look = render::visualVolumes(m, scene_.visuals, q_);
    volumes.insert(volumes.end(), std::make_move_iterator(look.begin()), std::make_move_iterator(look.end()));
  }
  const render::Frame layer = renderer_->render(volumes, style_, true, false);
  for (std::size_t i = 0; i < checked; ++i) rec.not_finite |= layer.visibility[i] == render::Visibility::NotFinite;
  if (rec.not_finite) rec.status = SafetyStatus::Colliding;  // an overflowed volume is unsafe
  render::compositeOver(bgr, layer.bgra);
  if (!set.plain) drawStatusLine(bgr, rec);
}

void FrameAnnotator::drawStatusLine(cv::Mat& bgr, const FrameRecord& rec) const {
  const AnnotatorSettings& set = scene_.settings;
  std::ostringstream s;
  char buf[64];
  std::snprintf(buf, sizeof buf, "t %.3f s", rec.time + set.time_offset);
  s << buf;
  if (rec.match == StateMatch::None) {
    s << "  NO STATE (outside the log or in a gap longer than " << messageNumber(set.max_gap, 3) << " s)";
  } else {
    s << " (" << toString(rec.match) << ")" << (set.swept ? "  swept" : "");
    if (rec.unsafe()) {
      s << "  UNSAFE: " << (rec.braking_failed ? "no braking box" : rec.not_finite ? "volume not finite" : toString(rec.query));
    } else {
      if (std::isfinite(rec.min_distance)) {
        std::snprintf(buf, sizeof buf, "  min distance %.4f m", rec.min_distance);
        s << buf;
      } else {
        s << "  no checked pairs";
      }
      if (!rec.pairs.empty()) {
        s << "  within margin: ";
        const auto& bodies = scene_.model.bodies;
        for (std::size_t i = 0; i < rec.pairs.size() && i < 3; ++i)
          s << (i ? ", " : "") << bodies[rec.pairs[i][0]].name << "-" << bodies[rec.pairs[i][1]].name;
        if (rec.pairs.size() > 3) s << " +" << rec.pairs.size() - 3;
      }
    }
  }
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = std::clamp(bgr.rows / 900.0, 0.35, 1.0);
  const int thick = std::max(1, static_cast<int>(std::lround(scale * 2)));
  int baseline = 0;
  const std::string text = s.str();
  const cv::Size size = cv::getTextSize(text, font, scale, thick, &baseline);
  const int pad = std::max(3, size.height / 2);
  const cv::Rect box =
      cv::Rect(pad, bgr.rows - size.height - baseline - 3 * pad, size.width + 2 * pad, size.height + baseline + 2 * pad) &
      cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (box.empty()) return;
  cv::Mat roi = bgr(box);
  roi.convertTo(roi, -1, 0.35, 0);  // darkened background keeps the text readable on any frame
  const cv::Point at(box.x + pad, box.y + pad + size.height);
  const cv::Scalar colour = rec.status == SafetyStatus::Clear ? cv::Scalar(255, 255, 255) : render::statusColour(rec.status);
  cv::putText(bgr, text, at, font, scale, colour, thick, cv::LINE_AA);
}

}  // namespace kccd::overlay
