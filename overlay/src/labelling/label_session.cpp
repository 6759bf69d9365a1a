#include "kccd/overlay/labelling/label_session.hpp"
#include "kccd/calib/image_encode.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include <opencv2/calib3d.hpp>

#include "kccd/file_reader.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_report.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/labelling/labelling_candidates.hpp"
#include "kccd/overlay/labelling/labels_document.hpp"
#include "kccd/render/model_view.hpp"

namespace kccd::overlay {

struct LabelSession::Frame {
  nlohmann::json document;              // the labels document as the page edits it
  std::optional<calib::Labels> labels;  // parsed; none while the document is empty
  std::vector<unsigned char> png;       // the picture
  nlohmann::json candidates;            // tags and corners (model points: per request)
  int overlay_revision = -1;            // the revision overlay_png and mask were drawn at
  std::vector<unsigned char> overlay_png;
  cv::Mat mask;                             // body i + 1 where body i's volume is nearest; empty: none drawn
  std::optional<nlohmann::json> recovered;  // the autosave found at the start, newer than the labels file
};

namespace {

nlohmann::json point(const cv::Point2d& p) { return {p.x, p.y}; }
nlohmann::json point(const cv::Point3d& p) { return {p.x, p.y, p.z}; }

nlohmann::json candidatesJson(const LabellingCandidates& c) {
  nlohmann::json tags = nlohmann::json::array(), corners = nlohmann::json::array(), models = nlohmann::json::array();
  for (const TagCandidate& t : c.tags) {
    nlohmann::json k = nlohmann::json::array();
    for (const cv::Point2d& p : t.corners) k.push_back(point(p));
    tags.push_back({{"id", t.id}, {"corners", std::move(k)}, {"placed", t.placed}});
  }
  for (const CornerCandidate& p : c.corners) corners.push_back({{"name", p.name}, {"pixel", point(p.pixel)}});
  for (const ModelPointCandidate& m : c.model_points)
    models.push_back({{"name", m.name},
                      {"body", m.body},
                      {"point", m.point},
                      {"body_point", {m.body_point.x(), m.body_point.y(), m.body_point.z()}},
                      {"world_fixed", m.world_fixed},
                      {"world", point(m.world)},
                      {"pixel", point(m.pixel)}});
  return {{"tags", std::move(tags)}, {"corners", std::move(corners)}, {"model_points", std::move(models)}};
}

// The autosave PATH.bak as a labels document when it is newer than PATH (or PATH is missing) and
// says something else: edits a session made and nobody saved. None when it cannot be read: a
// backup that is not labels is not offered.
std::optional<nlohmann::json> newerAutosave(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string bak = path + ".bak";
  std::error_code ec;
  if (path.empty() || !fs::is_regular_file(bak, ec)) return std::nullopt;
  const bool has_labels = fs::exists(path, ec);
  if (has_labels && !(fs::last_write_time(bak, ec) > fs::last_write_time(path, ec))) return std::nullopt;
  try {
    const calib::Labels recovered = calib::loadLabels(bak);
    if (has_labels && labelsJson(calib::loadLabels(path)) == labelsJson(recovered)) return std::nullopt;
    return labelsJson(recovered);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::vector<unsigned char> encodePng(const cv::Mat& image) {
  const std::vector<std::uint8_t> png = calib::encodePng(image);
  return {png.begin(), png.end()};
}

}  // namespace

LabelSession::LabelSession(LabelSessionInputs inputs) : in_(std::move(inputs)) {
  if (in_.frames.empty()) throw std::invalid_argument("LabelSession: no frames");
  if (!in_.masks.empty()) {
    if (in_.masks.size() != in_.frames.size() || in_.mask_names.size() != in_.masks.size() || !in_.model)
      throw std::invalid_argument("LabelSession: masks need a model, and one mask and one name per frame");
    for (const cv::Mat& m : in_.masks)
      if (m.type() != CV_8UC1 || m.cols != in_.intrinsics.width || m.rows != in_.intrinsics.height)
        throw std::invalid_argument("LabelSession: a mask is not 8-bit one-channel of the camera's size");
    for (std::size_t i = 0; i < in_.frames.size(); ++i)
      if (!in_.frames[i].state)
        throw CalibInputError("--masks: frame " + std::to_string(i + 1) + " (" + in_.frames[i].name +
                              ") has no state: the masks are matched by the model drawn at each frame's state");
  }
  frames_.resize(in_.frames.size());
  for (std::size_t i = 0; i < in_.frames.size(); ++i) {
    const LabelFrame& f = in_.frames[i];
    Frame& s = frames_[i];
    checkPicture(f.bgr, in_.intrinsics, f.name, in_.intrinsics_name);
    if (std::filesystem::exists(f.labels_path)) {
      s.labels = calib::loadLabels(f.labels_path);
      s.document = labelsJson(*s.labels);
    } else {
      s.document = nlohmann::json{{"labels", nlohmann::json::array()}};
    }
    s.recovered = newerAutosave(f.labels_path);
    s.png = encodePng(f.bgr);
    CandidateInputs c;
    c.image = f.name;
    c.tags = in_.tags;
    c.corners = in_.corners;
    s.candidates = candidatesJson(labellingCandidates(f.bgr, c));
  }
  resolve();
}

LabelSession::~LabelSession() = default;

std::size_t LabelSession::frameCount() const { return frames_.size(); }

void LabelSession::resolve() {
  GatherInputs g;
  g.camera = in_.intrinsics;
  g.camera_name = in_.intrinsics_name;
  g.tags = in_.tags;
  g.model = in_.model;
  for (std::size_t i = 0; i < in_.frames.size(); ++i) {
    CalibFrame f;
    f.image = in_.frames[i].name;
    f.bgr = in_.frames[i].bgr;
    f.labels = frames_[i].labels;
    f.state = in_.frames[i].state;
    g.frames.push_back(std::move(f));
  }
  const Gathered gathered = gatherCorrespondences(g);
  CalibSolution s = solveCalibration(in_.intrinsics, gathered, in_.pose, in_.model);
  // Snapping: the solve refined to the masks; without a start (fewer than 4 points), said. Kept
  // in a local until everything else has been computed, so a throw leaves the last solve whole.
  std::optional<Refinement> refinement;
  std::string snap_message;
  if (snap_) {
    RefineInputs masks;
    masks.masks = in_.masks;
    masks.mask_names = in_.mask_names;
    masks.bodies = in_.mask_bodies;
    try {
      refinement = refineCalibration(s, gathered, in_.intrinsics, *in_.model, masks);
      snap_message = refinement->result.message;
    } catch (const CalibInputError& e) {
      snap_message = e.what();
    }
  }
  nlohmann::json report = calibReport(gathered, s, {.camera = s.solved() ? in_.camera_output : std::string()});
  report["snap"] = {{"available", !in_.masks.empty()}, {"on", snap_}, {"message", snap_message}};
  if (refinement) report["refinement"] = refinementJson(*refinement);
  report["rms_px"] = s.solved() && s.pose.camera.reprojection_rms_px
                         ? nlohmann::json(*s.pose.camera.reprojection_rms_px)
                         : nlohmann::json(nullptr);
  report["revision"] = revision_;
  // Per point, its frame, where it was seen and, when solved, where the pose projects it (the page
  // draws the residual vectors).
  nlohmann::json& residuals = report["residuals"];
  for (std::size_t i = 0; i < gathered.points.size() && i < residuals.size(); ++i) {
    residuals[i]["frame"] = gathered.sources[i].frame;
    residuals[i]["pixel"] = point(gathered.points[i].pixel);
    residuals[i]["projected"] = nullptr;
    if (!s.solved()) continue;
    const calib::Camera& c = s.pose.camera;
    const cv::Point3d& w = gathered.points[i].world;
    cv::Matx33d rot;
    cv::Rodrigues(c.rvec, rot);
    const cv::Vec3d in_camera = rot * cv::Vec3d(w.x, w.y, w.z) + c.tvec;
    if (!(in_camera[2] > 1e-9)) continue;  // behind the camera: no projection
    std::vector<cv::Point2d> projected;
    cv::projectPoints(std::vector<cv::Point3d>{w}, c.rvec, c.tvec, c.camera_matrix, c.distortion, projected);
    residuals[i]["projected"] = point(projected[0]);
  }
  solve_json_ = std::move(report);
  solved_ = s.solved() ? std::optional<calib::Camera>(s.pose.camera) : std::nullopt;
  refinement_ = std::move(refinement);
}

nlohmann::json LabelSession::session() const {
  nlohmann::json frames = nlohmann::json::array();
  for (std::size_t i = 0; i < in_.frames.size(); ++i) {
    const LabelFrame& f = in_.frames[i];
    nlohmann::json candidates = frames_[i].candidates;
    if (solved_ && in_.model && f.state) candidates["model_points"] = modelPoints(i);
    frames.push_back({{"index", i},
                      {"name", f.name},
                      {"image", "/frame/" + std::to_string(i) + ".png"},
                      {"width", f.bgr.cols},
                      {"height", f.bgr.rows},
                      {"state", f.state ? nlohmann::json(*f.state) : nlohmann::json(nullptr)},
                      {"labels_file", f.labels_path},
                      {"labels", frames_[i].document},
                      {"candidates", std::move(candidates)},
                      {"recovered", frames_[i].recovered ? nlohmann::json{{"file", f.labels_path + ".bak"},
                                                                          {"labels", *frames_[i].recovered}}
                                                         : nlohmann::json(nullptr)}});
  }
  nlohmann::json bodies = nlohmann::json::array();
  if (in_.model) {
    for (const Body& b : in_.model->bodies) {
      nlohmann::json pts = nlohmann::json::array();
      for (const Vec3& p : b.points) pts.push_back({p.x(), p.y(), p.z()});
      bodies.push_back({{"name", b.name},
                        {"frame", b.frame == kWorld ? std::string("world")
                                                    : in_.model->joints[static_cast<std::size_t>(b.frame)].name},
                        {"world_fixed", b.frame == kWorld},
                        {"points", std::move(pts)}});
    }
  }
  // The layout's tag corners in the world: targets for the corners of a tag the detector missed.
  nlohmann::json layout = nlohmann::json::array();
  if (in_.tags)
    for (const calib::Tag& t : in_.tags->tags) {
      nlohmann::json corners = nlohmann::json::array();
      for (const cv::Point3d& c : t.corners()) corners.push_back(point(c));
      layout.push_back({{"id", t.id}, {"size", t.size}, {"corners", std::move(corners)}});
    }
  nlohmann::json out;
  out["frames"] = frames;
  out["layout"] = std::move(layout);
  out["labels"] = frames[0]["labels"];
  out["candidates"] = frames[0]["candidates"];
  out["bodies"] = std::move(bodies);
  out["solve"] = solve_json_;
  out["revision"] = revision_;
  out["dirty"] = dirty_;
  out["camera_output"] = in_.camera_output.empty() ? nlohmann::json(nullptr) : nlohmann::json(in_.camera_output);
  return out;
}

nlohmann::json LabelSession::putLabels(std::size_t frame, const nlohmann::json& document) {
  Frame& f = frames_.at(frame);
  std::optional<calib::Labels> labels;
  if (!emptyLabels(document)) labels = parseLabelsDocument(document, in_.frames[frame].labels_path);
  std::optional<calib::Labels> old = std::move(f.labels);
  f.labels = std::move(labels);
  ++revision_;
  try {
    resolve();
  } catch (...) {
    f.labels = std::move(old);  // nothing changes: the previous solve stands
    --revision_;
    throw;
  }
  f.document = labelsJson(f.labels ? *f.labels : calib::Labels{});
  dirty_ = true;
  f.recovered.reset();  // an autosave offered at the start is replaced by this one
  const std::string& path = in_.frames[frame].labels_path;
  if (f.labels && !path.empty()) writeFileAtomically(path + ".bak", labelsYaml(f.document, path));
  return solve_json_;
}

nlohmann::json LabelSession::setSnap(bool on) {
  if (in_.masks.empty()) throw std::logic_error("the session has no robot masks to snap to (kccd calib label --masks)");
  if (on == snap_) return solve_json_;
  const bool old = snap_;
  snap_ = on;
  ++revision_;
  try {
    resolve();
  } catch (...) {
    snap_ = old;
    --revision_;
    throw;
  }
  dirty_ = true;  // what Save writes has changed
  return solve_json_;
}

nlohmann::json LabelSession::modelPoints(std::size_t frame) const {
  const LabelFrame& f = in_.frames.at(frame);
  if (!solved_ || !in_.model || !f.state) return nlohmann::json::array();
  // The model's core points where the current estimate projects them.
  CandidateInputs c;
  c.image = f.name;
  c.corners = 0;
  c.camera = *solved_;
  c.camera_name = in_.intrinsics_name;
  c.model = in_.model;
  c.state = *f.state;
  return candidatesJson(labellingCandidates(f.bgr, c))["model_points"];
}

nlohmann::json LabelSession::pick(std::size_t frame, double u, double v) {
  overlayPng(frame);  // draws this revision's mask when it is not drawn yet
  const Frame& f = frames_.at(frame);
  nlohmann::json out{{"body", nullptr}, {"points", nlohmann::json::array()}, {"revision", revision_}};
  if (f.mask.empty() || !(std::abs(u) < 1e9) || !(std::abs(v) < 1e9)) return out;
  const long x = std::lround(u), y = std::lround(v);  // pixel centres at integers
  if (x < 0 || y < 0 || x >= f.mask.cols || y >= f.mask.rows) return out;
  const std::size_t label = f.mask.at<std::uint8_t>(static_cast<int>(y), static_cast<int>(x));
  if (label == 0 || label > in_.model->bodies.size()) return out;
  const std::string& body = in_.model->bodies[label - 1].name;
  out["body"] = body;
  std::vector<std::pair<double, nlohmann::json>> near;
  for (nlohmann::json& p : modelPoints(frame)) {
    if (p["body"] != body) continue;
    const double d = std::hypot(p["pixel"][0].get<double>() - u, p["pixel"][1].get<double>() - v);
    p["distance_px"] = d;
    near.emplace_back(d, std::move(p));
  }
  std::stable_sort(near.begin(), near.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [d, p] : near) out["points"].push_back(std::move(p));
  return out;
}

const std::vector<unsigned char>& LabelSession::framePng(std::size_t frame) const { return frames_.at(frame).png; }

const std::vector<unsigned char>& LabelSession::overlayPng(std::size_t frame) {
  Frame& f = frames_.at(frame);
  if (f.overlay_revision == revision_) return f.overlay_png;
  const LabelFrame& in = in_.frames[frame];
  cv::Mat layer;
  if (solved_ && in_.model && in.state) {
    render::ModelView view(*in_.model, *solved_);
    render::ModelViewRequest request;
    request.state = *in.state;
    request.tight_volumes = false;
    request.mask = true;  // which body is where: pick()
    request.style.labels = in_.model->bodies.size() <= 12;
    request.style.legend = false;
    render::ModelFrame drawn = view.draw(request);
    layer = std::move(drawn.images.bgra);
    f.mask = std::move(drawn.images.mask);
    if (refinement_ && frame < in_.masks.size()) {
      // The mask's outline and the drawn robot's, opaque over the volumes.
      cv::Mat lines = cv::Mat::zeros(layer.rows, layer.cols, CV_8UC3);
      drawMaskAgreement(
          lines, *solved_, in_.masks[frame], calib::placeVolumes(*in_.model, *in.state, in_.mask_bodies),
          frame < refinement_->meshes.size() ? refinement_->meshes[frame] : std::vector<calib::PlacedMesh>{});
      for (int y = 0; y < lines.rows; ++y)
        for (int x = 0; x < lines.cols; ++x)
          if (const cv::Vec3b c = lines.at<cv::Vec3b>(y, x); c != cv::Vec3b(0, 0, 0)) {
            // Anti-aliased edges: the line's colour at full strength over the volumes with its
            // coverage (straight alpha both).
            const double a = std::max({c[0], c[1], c[2]}) / 255.0;
            cv::Vec4b& under = layer.at<cv::Vec4b>(y, x);
            const double ua = under[3] / 255.0, out_a = a + (1.0 - a) * ua;
            for (int k = 0; k < 3; ++k)
              under[k] =
                  cv::saturate_cast<unsigned char>((c[k] / std::max(a, 1e-9) * a + under[k] * ua * (1.0 - a)) / out_a);
            under[3] = cv::saturate_cast<unsigned char>(255.0 * out_a);
          }
    }
  } else {
    layer = cv::Mat(in.bgr.rows, in.bgr.cols, CV_8UC4, cv::Scalar(0, 0, 0, 0));
    f.mask = cv::Mat();
  }
  f.overlay_png = encodePng(layer);
  f.overlay_revision = revision_;
  return f.overlay_png;
}

LabelSaved LabelSession::save() {
  LabelSaved saved;
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    const Frame& f = frames_[i];
    if (!f.labels) continue;
    const std::string& path = in_.frames[i].labels_path;
    const std::string text = labelsYaml(f.document, path);
    if (std::filesystem::exists(path)) {
      const std::string previous = readRegularFile(path, calib::kMaxLabelsBytes, "labels file");
      if (previous == text) {
        saved.labels.push_back(path);
        continue;  // unchanged: no new backup either
      }
      writeFileAtomically(path + ".bak", previous);
      saved.backups.push_back(path + ".bak");
    }
    writeFileAtomically(path, text);
    saved.labels.push_back(path);
  }
  if (solved_ && !in_.camera_output.empty()) {
    writeFileAtomically(in_.camera_output,
                        calib::cameraText(*solved_) + (refinement_ ? refinementText(*refinement_) : std::string()));
    saved.camera = in_.camera_output;
  }
  dirty_ = false;
  return saved;
}

}  // namespace kccd::overlay
