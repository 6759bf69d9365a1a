#include "kccd/overlay/recording/frame_annotator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include <opencv2/imgproc.hpp>

#include "kccd/input_error.hpp"

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
  request.style.legend = !set.plain;
  request.onto = &bgr;  // the layer composited in the warp's pass
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
  const Clock::time_point t_composite = Clock::now();
  if (!set.plain) drawStatusLine(bgr, rec);
  rec.times.composite = since(t_composite);
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
      s << "  UNSAFE: "
        << (rec.braking_failed ? "no braking box"
            : rec.not_finite   ? "volume not finite"
                               : toString(rec.query));
    } else {
      if (std::isfinite(rec.min_distance)) {
        std::snprintf(buf, sizeof buf, "  min distance %.4f m", rec.min_distance);
        s << buf;
      } else {
        s << "  no checked pairs";
      }
      if (!rec.pairs.empty()) {
        s << "  within margin: ";
        const std::vector<std::array<std::string, 2>> links = linkPairs(scene_.model, rec.pairs);
        for (std::size_t i = 0; i < links.size() && i < 3; ++i)
          s << (i ? ", " : "") << links[i][0] << "-" << links[i][1];
        if (links.size() > 3) s << " +" << links.size() - 3;
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
  const cv::Rect box = cv::Rect(pad, bgr.rows - size.height - baseline - 3 * pad, size.width + 2 * pad,
                                size.height + baseline + 2 * pad) &
                       cv::Rect(0, 0, bgr.cols, bgr.rows);
  if (box.empty()) return;
  // The background darkened (keeps the text readable on any frame): each byte times 0.35, rounded
  // as convertTo rounds, through a table made by convertTo itself (a table look-up per byte is
  // several times faster than convertTo's arithmetic on a strip of the image).
  static const cv::Mat darken = [] {
    cv::Mat ramp(1, 256, CV_8U), out;
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = static_cast<uchar>(i);
    ramp.convertTo(out, -1, 0.35, 0);
    return out;
  }();
  cv::Mat roi = bgr(box);
  cv::LUT(roi, darken, roi);
  const cv::Point at(box.x + pad, box.y + pad + size.height);
  const cv::Scalar colour =
      rec.status == SafetyStatus::Clear ? cv::Scalar(255, 255, 255) : render::statusColour(rec.status);
  cv::putText(bgr, text, at, font, scale, colour, thick, cv::LINE_AA);
}

}  // namespace kccd::overlay
