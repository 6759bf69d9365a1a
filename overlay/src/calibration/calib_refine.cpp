#include "kccd/overlay/calibration/calib_refine.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "kccd/calib/background.hpp"
#include "kccd/calib/pose_difference.hpp"
#include "kccd/format_number.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/render/visuals.hpp"

namespace kccd::overlay {
namespace {

// A pose from four or more points without the solve's gates (rough clicks give one the solve
// refuses): SQPnP on all of them.
std::optional<calib::Camera> roughPose(const calib::Camera& intrinsics, const Gathered& g) {
  if (g.points.size() < 4) return std::nullopt;
  std::vector<cv::Point3d> world;
  std::vector<cv::Point2d> pixels;
  for (const calib::Correspondence& c : g.points) world.push_back(c.world), pixels.push_back(c.pixel);
  cv::Vec3d rvec, tvec;
  try {
    if (!cv::solvePnP(world, pixels, intrinsics.camera_matrix, intrinsics.distortion, rvec, tvec, false,
                      cv::SOLVEPNP_SQPNP))
      return std::nullopt;
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  if (!std::isfinite(cv::norm(rvec)) || !std::isfinite(cv::norm(tvec))) return std::nullopt;
  calib::Camera c = intrinsics;
  c.rvec = rvec, c.tvec = tvec;
  c.reprojection_rms_px.reset(), c.rotation_sigma_deg.reset(), c.position_sigma_m.reset();
  return c;
}

// The refinement to masks made from the recording, remade around the pose as it is refined: the
// robot's drawing widened by a tenth of the image's diagonal first (a start 10 degrees off moves
// the robot about that far), then by 3 % and 1.5 % of it around the refined pose. Each round's
// background comes from the samples away from the robot at that pose, and the fit runs over the
// gathered frames and 16 of the samples together (many poses pin the camera better than a few). The
// rounds before the last are kept on any gain (their masks are rough); the last is held to the
// refinement's gates. The result is the last round that improved the pose, with the gathered
// frames' figures (IoUs before at `start`) and their masks in `out`.
calib::RefineResult refineToRecording(const calib::Camera& start, std::vector<calib::MaskFrame> frames,
                                      const Gathered& g, std::span<const RecordingSample> recording,
                                      const RobotDrawing& robot, std::span<const int> bodies, const Model& model,
                                      const calib::RefineOptions& options, const FieldSpelling& spell,
                                      Refinement& out) {
  const auto named = [&](const std::string& field) { return spelledField(spell, field); };
  const std::size_t gathered = frames.size();
  std::vector<const cv::Mat*> pictures;
  for (const GatheredFrame& f : g.frames) pictures.push_back(&f.bgr);
  std::vector<std::vector<calib::PlacedVolume>> frame_volumes, sample_volumes;  // all the bodies, for the regions
  for (const GatheredFrame& f : g.frames) frame_volumes.push_back(calib::placeVolumes(model, f.state, bodies));
  for (const RecordingSample& s : recording) {
    if (s.bgr.type() != CV_8UC3 || s.bgr.cols != start.width || s.bgr.rows != start.height)
      throw CalibInputError(named("masks") +
                            " auto: the recording's frames are not 8-bit colour pictures of the camera's " +
                            std::to_string(start.width) + "x" + std::to_string(start.height));
    if (static_cast<int>(s.state.size()) != model.stateSize())
      throw CalibInputError(named("masks") + " auto: a frame of the recording without a state of the model's " +
                            std::to_string(model.stateSize()) + " values");
    sample_volumes.push_back(calib::placeVolumes(model, s.state, bodies));
  }
  // The samples fitted with the gathered frames: 16 spread over the recording.
  const std::size_t fitted = std::min<std::size_t>(recording.size(), 16);
  std::vector<std::size_t> fitted_sample;
  for (std::size_t i = 0; i < fitted; ++i) {
    const std::size_t k = i * recording.size() / fitted;
    fitted_sample.push_back(k);
    pictures.push_back(&recording[k].bgr);
    frames.push_back({cv::Mat(), robot.volumes(recording[k].state), robot.meshes(recording[k].state)});
  }
  const double diagonal = std::hypot(start.width, start.height);
  const std::vector<double> widths = {0.10, 0.03, 0.015};
  calib::Camera cam = start;
  std::optional<calib::RefineResult> kept;
  std::size_t kept_round = 0;
  calib::RefineResult last;
  cv::Mat known;  // the kept round's
  for (std::size_t round = 0; round < widths.size(); ++round) {
    // Where the robot may be in each sample and each gathered frame; a fitted sample's is its sample's.
    std::vector<calib::BackgroundSample> samples;
    for (std::size_t k = 0; k < recording.size(); ++k)
      samples.push_back({recording[k].bgr, calib::robotRegion(cam, sample_volumes[k], widths[round] * diagonal)});
    std::vector<cv::Mat> regions;
    for (const auto& v : frame_volumes) regions.push_back(calib::robotRegion(cam, v, widths[round] * diagonal));
    for (const std::size_t k : fitted_sample) regions.push_back(samples[k].robot);
    const calib::Background background = calib::estimateBackground(samples);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      frames[f].mask = calib::foregroundMask({*pictures[f], regions[f]}, background);
      frames[f].known = background.known;
    }
    calib::RefineOptions o = options;
    if (round + 1 < widths.size()) o.min_iou = 0.0, o.max_rotation_sigma_deg = 90.0, o.max_frame_drop = 1.0;
    if (round > 0) o.start_is_prior = false;  // the masks were remade around a refined pose
    last = calib::refineToMasks(cam, frames, o);
    if (!last.improved) break;
    kept = last, kept_round = round, cam = last.camera;
    out.masks.clear();
    for (std::size_t f = 0; f < gathered; ++f) out.masks.push_back(frames[f].mask);
    known = background.known;
  }
  out.masks_from = "masks from the recording's background over " + std::to_string(recording.size()) + " frames, " +
                   std::to_string(fitted) + " of them fitted too";
  // A round before the last was kept on any gain: it is a camera only if it passes the gates the
  // last round would have held it to.
  if (kept && kept_round + 1 < widths.size()) {
    double mean = 0.0;
    for (const calib::FrameAgreement& a : kept->frames) mean += a.iou_after / static_cast<double>(kept->frames.size());
    if (mean < options.min_iou || !(kept->camera.rotation_sigma_deg.value_or(90.0) <= options.max_rotation_sigma_deg)) {
      last.message = "the drawn robot and the masks made from the recording agree too little (mean IoU " +
                     formatNumber(mean, 3) + ", at least " + formatNumber(options.min_iou, 3) + " needed; rotation +-" +
                     formatNumber(kept->camera.rotation_sigma_deg.value_or(90.0), 3) +
                     " deg): is the camera fixed, and does the robot move over the recording? The start is kept";
      kept.reset();
    }
  }
  if (!kept) {
    // The start's figures against the masks of the first round (made around it).
    last.improved = false, last.camera = start, last.covariance = cv::Matx66d::zeros();
    if (out.masks.empty())
      for (std::size_t f = 0; f < gathered; ++f) out.masks.push_back(frames[f].mask);
    if (known.empty()) known = frames.front().known;
  }
  calib::RefineResult result = kept ? *kept : last;
  result.frames.resize(gathered);
  // The agreement before: the start's drawing against the masks the result was made to.
  for (std::size_t f = 0; f < gathered; ++f) {
    const cv::Mat drawn = frames[f].meshes.empty() ? calib::drawSilhouette(start, frames[f].volumes).mask
                                                   : calib::drawMeshSilhouette(start, frames[f].meshes).mask;
    result.frames[f].iou_before = calib::maskIou(drawn & known, out.masks[f] & known);
    if (!kept) result.frames[f].iou_after = result.frames[f].iou_before;
  }
  if (kept)
    out.masks_from += " (the background known over " +
                      formatNumber(100.0 * cv::countNonZero(known) / static_cast<double>(known.total()), 3) +
                      " % of the image)";
  return result;
}

}  // namespace

std::vector<int> movingBodies(const Model& model, std::span<const int> bodies) {
  std::vector<int> out;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    if (!bodies.empty() && std::find(bodies.begin(), bodies.end(), static_cast<int>(b)) == bodies.end()) continue;
    bool moves = false;
    for (int j = model.bodies[b].frame; j != kWorld && !moves; j = model.joints[static_cast<std::size_t>(j)].parent)
      moves = model.joints[static_cast<std::size_t>(j)].dof > 0;
    if (moves) out.push_back(static_cast<int>(b));
  }
  return out;
}

RobotDrawing::RobotDrawing(const Model& model, std::vector<int> bodies, const std::string& draw)
    : model_(model), bodies_(std::move(bodies)), drawn_("collision volumes") {
  if (draw != "auto" && draw != "visuals" && draw != "volumes")
    throw CalibInputError("draw: '" + draw + "' is not auto, visuals or volumes");
  if (draw != "volumes" && !model.visuals.empty()) {
    try {
      visuals_ = render::loadVisuals(model);
      drawn_ = "visual meshes";
    } catch (const render::VisualError& e) {
      if (draw == "visuals") throw;
      drawn_ = std::string("collision volumes (the visuals could not be read: ") + e.what() + ")";
    }
  } else if (draw == "visuals") {
    throw CalibInputError("draw visuals: the model has no visuals: (draw its collision volumes instead)");
  } else if (!model.visuals.empty()) {
    drawn_ = "collision volumes (asked for)";
  }
  // With visuals, the volumes that stand for them: the bodies in frames that carry one.
  volume_bodies_ = bodies_;
  if (volume_bodies_.empty())
    for (std::size_t b = 0; b < model.bodies.size(); ++b) volume_bodies_.push_back(static_cast<int>(b));
  if (!visuals_.empty()) {
    std::vector<int> shown;
    for (const int b : volume_bodies_)
      if (std::any_of(visuals_.begin(), visuals_.end(), [&](const render::LoadedVisual& v) {
            return v.frame == model.bodies[static_cast<std::size_t>(b)].frame;
          }))
        shown.push_back(b);
    if (!shown.empty()) volume_bodies_ = std::move(shown);
  }
}

std::vector<calib::PlacedVolume> RobotDrawing::volumes(std::span<const double> state) const {
  return calib::placeVolumes(model_, state, volume_bodies_);
}

std::vector<calib::PlacedMesh> RobotDrawing::meshes(std::span<const double> state) const {
  if (visuals_.empty()) return {};
  std::vector<Pose> poses(model_.joints.size());
  if (!framePoses(model_, state, poses)) return {};
  std::vector<calib::PlacedMesh> out;
  for (const render::LoadedVisual& v : visuals_) {
    const bool shown = bodies_.empty() || std::any_of(bodies_.begin(), bodies_.end(), [&](int b) {
                         return model_.bodies[static_cast<std::size_t>(b)].frame == v.frame;
                       });
    if (!shown || !v.mesh) continue;
    const Pose& at = framePose(poses, v.frame);
    calib::PlacedMesh m;
    m.vertices.reserve(v.mesh->vertices.size());
    for (const Vec3& p : v.mesh->vertices) m.vertices.push_back(at * p);
    m.triangles = v.mesh->triangles;
    out.push_back(std::move(m));
  }
  return out;
}

Refinement refineCalibration(CalibSolution& solution, const Gathered& g, const calib::Camera& intrinsics,
                             const Model& model, const RefineInputs& in, const calib::Camera* truth) {
  const auto named = [&](const std::string& field) { return spelledField(in.spell, field); };
  const bool edges = in.source == calib::RefineSource::Edges;
  const bool from_recording = !edges && in.masks.empty() && !in.recording.empty();
  if (!edges && !from_recording && in.masks.size() != g.frames.size())
    throw CalibInputError(named("masks") + ": " + std::to_string(in.masks.size()) + " mask(s) for " +
                          std::to_string(g.frames.size()) + " frame(s): give one mask per frame, in the same order");
  Refinement out;
  // Masks made from a recording hold only what moves.
  std::vector<int> bodies = in.bodies;
  if (from_recording) {
    bodies = movingBodies(model, in.bodies);
    if (bodies.empty())
      throw CalibInputError(named("masks") +
                            " auto: no body of the model (of those the masks show) moves with a joint");
  }
  const RobotDrawing robot(model, bodies, in.draw);
  out.bodies = bodies;
  out.drawn = robot.drawn();
  std::vector<calib::MaskFrame> mask_frames;
  std::vector<calib::EdgeFrame> edge_frames;
  const std::string what = edges ? named("refine") + " edges" : named("masks") + (from_recording ? " auto" : "");
  for (std::size_t f = 0; f < g.frames.size(); ++f) {
    const std::vector<double>& state = g.frames[f].state;
    if (static_cast<int>(state.size()) != model.stateSize())
      throw CalibInputError(what + ": frame " + std::to_string(f + 1) + " has no state of the model's " +
                            std::to_string(model.stateSize()) + " values: give " + named("state") + ", or " +
                            named("states") + " with " + named("time"));
    if ((edges || from_recording) && g.frames[f].bgr.empty())
      throw CalibInputError(what + ": frame " + std::to_string(f + 1) + " has no picture to find " +
                            (edges ? "edges" : "the robot") + " in: give " + named("image") + " or " + named("video"));
    std::vector<calib::PlacedMesh> meshes = robot.meshes(state);
    out.meshes.push_back(meshes);
    if (edges)
      edge_frames.push_back({g.frames[f].bgr, robot.volumes(state), std::move(meshes)});
    else
      mask_frames.push_back({from_recording ? cv::Mat() : in.masks[f], robot.volumes(state), std::move(meshes)});
  }
  calib::Camera start;
  if (solution.solved()) {
    start = solution.pose.camera, out.start = "solve";
  } else if (const std::optional<calib::Camera> rough = roughPose(intrinsics, g)) {
    start = *rough, out.start = "points";
  } else if (in.rough) {
    start = intrinsics;
    start.rvec = in.rough->rvec, start.tvec = in.rough->tvec;
    out.start = "camera";
  } else {
    throw CalibInputError(what + ": no start for the pose: give 4 or more labels or tag corners, or " +
                          named("camera") + " ROUGH.yaml");
  }
  if (edges) {
    calib::EdgeOptions options;
    options.start_is_prior = out.start == "solve";
    out.result = calib::refineToEdges(start, edge_frames, options, g.points);
  } else {
    calib::RefineOptions options;
    options.start_is_prior = out.start == "solve";
    out.result = from_recording ? refineToRecording(start, mask_frames, g, in.recording, robot, bodies, model, options,
                                                    in.spell, out)
                                : calib::refineToMasks(start, mask_frames, options);
  }
  if (!out.result.improved) return out;

  calib::PoseResult& pose = solution.pose;
  pose.camera = out.result.camera;
  pose.covariance = out.result.covariance;
  pose.status = calib::PoseStatus::Solved;
  // Every point's residual under the refined pose; those far off are named: farther than 3 times
  // the outline's rms, 3 times the other clicks' median residual (rough clicks are all a few
  // pixels off: a misclick is off by much more than the others) and 4 px.
  double outline_rms = 0.0;
  for (const calib::FrameAgreement& a : out.result.frames) outline_rms = std::max(outline_rms, a.rms_px);
  pose.residuals.clear();
  pose.rejected.clear();
  if (!g.points.empty()) {
    std::vector<cv::Point3d> world;
    for (const calib::Correspondence& c : g.points) world.push_back(c.world);
    std::vector<cv::Point2d> px;
    cv::projectPoints(world, pose.camera.rvec, pose.camera.tvec, pose.camera.camera_matrix, pose.camera.distortion, px);
    std::vector<double> d(g.points.size());
    for (std::size_t i = 0; i < g.points.size(); ++i)
      d[i] = std::hypot(px[i].x - g.points[i].pixel.x, px[i].y - g.points[i].pixel.y);
    // The median of the other points' residuals: a misclick does not raise its own limit.
    const auto othersMedian = [&d](std::size_t skip) {
      std::vector<double> others;
      for (std::size_t k = 0; k < d.size(); ++k)
        if (k != skip && std::isfinite(d[k])) others.push_back(d[k]);
      if (others.empty()) return 0.0;
      std::sort(others.begin(), others.end());
      const std::size_t n = others.size();
      return n % 2 ? others[n / 2] : 0.5 * (others[n / 2 - 1] + others[n / 2]);
    };
    for (std::size_t i = 0; i < g.points.size(); ++i) {
      const double limit = std::max({4.0, 3.0 * outline_rms, 3.0 * othersMedian(i)});
      const bool agrees = std::isfinite(d[i]) && d[i] <= limit;
      pose.residuals.push_back({g.points[i].name, d[i], agrees});
      if (!agrees) out.disagreeing.push_back(g.points[i].name), pose.rejected.push_back(g.points[i].name);
    }
  }
  pose.inliers = static_cast<int>(g.points.size() - out.disagreeing.size());
  // The points' RMS under the refined pose, over those the image agrees with (none: unknown).
  double sse = 0.0;
  for (const calib::Residual& res : pose.residuals)
    if (res.inlier) sse += res.px * res.px;
  if (pose.inliers > 0)
    pose.camera.reprojection_rms_px = std::sqrt(sse / pose.inliers);
  else
    pose.camera.reprojection_rms_px.reset();
  pose.message = out.result.message;
  if (!out.disagreeing.empty()) {
    pose.message += "; the image disagrees with";
    for (const std::string& n : out.disagreeing) pose.message += " " + n;
  }
  if (truth) solution.truth_error = calib::poseDifference(pose.camera, *truth);
  solution.volume_sigma_px.reset();
  return out;
}

std::string refinementText(const Refinement& m) {
  const bool edges = m.result.source == calib::RefineSource::Edges;
  std::string before = "[", after = "[";
  for (std::size_t f = 0; f < m.result.frames.size(); ++f) {
    const calib::FrameAgreement& a = m.result.frames[f];
    before += (f ? ", " : " ") + formatNumber(edges ? a.matched_before : a.iou_before, 6);
    after += (f ? ", " : " ") + formatNumber(edges ? a.matched_after : a.iou_after, 6);
  }
  const std::string key = edges ? "edge_share" : "mask_iou";
  return std::string("refinement: ") + (m.result.improved ? (edges ? "edges" : "masks") : "none") +
         "\nrefinement_start: " + m.start + "\nrefinement_drawn: \"" + m.drawn + "\"\n" +
         (m.masks_from.empty() ? std::string() : "refinement_masks: \"" + m.masks_from + "\"\n") + key +
         "_before: " + before + " ]\n" + key + "_after: " + after + " ]\n";
}

nlohmann::json refinementJson(const Refinement& m) {
  nlohmann::json j;
  const bool edges = m.result.source == calib::RefineSource::Edges;
  j["source"] = edges ? "edges" : "masks";
  j["improved"] = m.result.improved;
  j["message"] = m.result.message;
  j["start"] = m.start;
  j["drawn"] = m.drawn;
  if (!m.masks_from.empty()) j["masks_from"] = m.masks_from;
  j["iterations"] = m.result.iterations;
  j["frames"] = nlohmann::json::array();
  for (const calib::FrameAgreement& a : m.result.frames) {
    nlohmann::json f = {{"rms_px", a.rms_px}, {"outline_points", a.outline_points}};
    if (edges)
      f["edge_share_before"] = a.matched_before, f["edge_share_after"] = a.matched_after;
    else
      f["iou_before"] = a.iou_before, f["iou_after"] = a.iou_after;
    j["frames"].push_back(f);
  }
  j["disagreeing"] = m.disagreeing;
  if (m.result.improved) {
    j["rotation_sigma_deg"] = *m.result.camera.rotation_sigma_deg;
    j["position_sigma_m"] = *m.result.camera.position_sigma_m;
  }
  return j;
}

void drawMaskAgreement(cv::Mat& bgr, const calib::Camera& camera, const cv::Mat& mask,
                       std::span<const calib::PlacedVolume> volumes, std::span<const calib::PlacedMesh> meshes) {
  if (bgr.empty()) return;
  const double sx = static_cast<double>(bgr.cols) / camera.width, sy = static_cast<double>(bgr.rows) / camera.height;
  const int thick =
      std::max(1, static_cast<int>(std::lround(std::min(sx, sy) * std::max(camera.width, camera.height) / 640.0)));
  auto outline = [&](const cv::Mat& m, const cv::Scalar& colour) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(m.clone(), contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
    for (auto& c : contours)
      for (cv::Point& p : c)
        p = cv::Point(static_cast<int>(std::lround(p.x * sx)), static_cast<int>(std::lround(p.y * sy)));
    cv::polylines(bgr, contours, true, colour, thick, cv::LINE_AA);
  };
  if (!mask.empty()) outline(mask != 0, cv::Scalar(0, 220, 255));
  outline(meshes.empty() ? calib::drawSilhouette(camera, volumes).mask : calib::drawMeshSilhouette(camera, meshes).mask,
          cv::Scalar(255, 0, 255));
}

}  // namespace kccd::overlay
