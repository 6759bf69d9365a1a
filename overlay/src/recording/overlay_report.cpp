// The overlay report as JSON (docs/formats.md section 9).
#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "kccd/overlay/recording/overlay_recording.hpp"

namespace kccd::overlay {
namespace {

nlohmann::json numberOrNull(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

nlohmann::json reportJson(const OverlayReport& report, const Model& model, bool with_frames) {
  nlohmann::json j;
  j["frames_total"] = report.frames.size();
  j["frames_written"] = report.written;
  j["no_state"] = report.no_state;
  j["colliding"] = report.colliding;
  j["within_margin"] = report.within_margin;
  j["unsafe"] = report.unsafe;
  j["volumes"] = report.swept ? "swept" : "static";
  j["time_offset"] = report.time_offset;
  if (report.time_offset_search)
    j["time_offset_auto"] = {{"range", {report.time_offset_search->first, report.time_offset_search->second}},
                             {"correlation", report.time_offset_found.correlation}};
  j["max_gap"] = report.max_gap;
  j["fps"] = report.fps > 0 ? nlohmann::json(report.fps) : nlohmann::json(nullptr);
  j["margin"] = report.margin;
  if (!report.source.empty()) {
    nlohmann::json& src = j["source"] = nlohmann::json::object();
    for (const auto& [key, value] : report.source)
      if (!value.empty()) src[key] = value;
  }
  if (report.timings) {
    const StageTimes& t = report.stages;
    j["timings"] = {{"setup", report.setup_seconds},
                    {"frames", report.seconds},
                    {"jobs", report.jobs},
                    {"reused", report.reused},
                    {"stage_seconds",
                     {{"decode", t.decode},
                      {"state", t.state},
                      {"query", t.query},
                      {"render", t.render},
                      {"read_back", t.read_back},
                      {"warp", t.warp},
                      {"composite", t.composite},
                      {"encode", t.encode}}}};
  }
  if (const AgreementSummary a = summariseAgreement(report.frames); a.frames > 0) {
    nlohmann::json low = nlohmann::json::array();
    for (std::size_t i = 0; i < std::min<std::size_t>(a.low.size(), 20); ++i) low.push_back(a.low[i]);
    j["mask_agreement"] = {{"frames", a.frames}, {"mean_iou", a.mean},       {"median_iou", a.median},
                           {"min_iou", a.min},   {"low_below", a.low_below}, {"low_frames", a.low.size()},
                           {"lowest", low}};
  }
  if (!with_frames) return j;
  nlohmann::json frames = nlohmann::json::array();
  for (std::size_t i = 0; i < report.frames.size(); ++i) {
    const FrameRecord& r = report.frames[i];
    nlohmann::json f;
    f["index"] = i;
    f["time"] = r.time;
    f["log_time"] = r.time + report.time_offset;
    f["state"] = toString(r.match);
    f["status"] = toString(r.status);
    f["min_distance"] = numberOrNull(r.min_distance);
    f["state_values"] = nlohmann::json::array();
    for (double v : r.values) f["state_values"].push_back(numberOrNull(v));
    f["pairs_within_margin"] = nlohmann::json::array();
    for (const auto& p : r.pairs)
      f["pairs_within_margin"].push_back({model.bodies[p[0]].name, model.bodies[p[1]].name});
    f["links_within_margin"] = nlohmann::json::array();
    for (const auto& l : linkPairs(model, r.pairs)) f["links_within_margin"].push_back({l[0], l[1]});
    if (r.match != StateMatch::None) f["query_status"] = r.queryStatusText();
    if (r.mask_iou) f["mask_iou"] = *r.mask_iou;
    f["written"] = r.written;
    frames.push_back(std::move(f));
  }
  j["frames"] = std::move(frames);
  return j;
}

}  // namespace kccd::overlay
