// `kccd calib`: the camera's pose in the world from AprilTags and labelled points in one or more
// frames, with its quality and a check image; `kccd calib sheet`: a labelling aid.
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "calib_drawing.hpp"
#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/calib/image_file.hpp"
#include "kccd/calib/labels.hpp"
#include "kccd/calib/pose.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/checker.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/overlay/video_source.hpp"
#include "kccd/render/renderer.hpp"
#include "kccd/render/scene.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

std::string num(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

void checkImageSize(const cv::Mat& img, const calib::Camera& cam, const std::string& path, const std::string& camera_path) {
  if (img.cols != cam.width || img.rows != cam.height)
    throw UsageError("--image " + path + ": the image is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                     " but the camera " + camera_path + " is " + std::to_string(cam.width) + "x" + std::to_string(cam.height));
}

// The camera file from --intrinsics with the bad-input message naming the option.
calib::Camera loadIntrinsics(const std::string& path) {
  calib::Camera cam = calib::loadCamera(path, calib::CameraPose::Optional);
  cam.rvec = cam.tvec = cv::Vec3d(0, 0, 0);
  cam.reprojection_rms_px.reset();
  cam.rotation_sigma_deg.reset();
  cam.position_sigma_m.reset();
  return cam;
}

// The world points of every body's core points at `state`.
std::vector<cv::Point3d> corePoints(const Model& m, std::span<const double> state, std::vector<std::string>* names = nullptr) {
  std::vector<Pose> poses(m.joints.size());
  std::vector<cv::Point3d> out;
  if (!framePoses(m, state, poses)) return out;
  for (const Body& b : m.bodies)
    for (std::size_t k = 0; k < b.points.size(); ++k) {
      const Vec3 p = framePose(poses, b.frame) * b.points[k];
      out.emplace_back(p.x(), p.y(), p.z());
      if (names) names->push_back(b.name + "." + std::to_string(k));
    }
  return out;
}

// ---------------------------------------------------------------------------------------------
// kccd calib

struct CalibArgs {
  std::string intrinsics, tags, model, output, check, truth;
  std::vector<std::string> images, labels, states;
  std::string state_log, ignore_columns, video;
  std::vector<double> times;
  std::vector<int> video_frames;
  double max_gap = 0.0;  // 0: 1.5 x the log's median period
  double threshold = 8.0, magnify = 20.0;
  int min_inliers = 6;
  bool json = false, quiet = false;
};

// One frame's contribution.
struct Frame {
  std::string image;  // path, or empty (labels only)
  cv::Mat bgr;
  std::vector<double> state;  // empty: none given
  std::vector<int> unknown_ids;
  int tag_points = 0, label_points = 0;
};

// Where a correspondence came from, for the report and the check image.
struct Source {
  std::size_t frame = 0;
  bool tag = false;
  std::string label;  // the label's name (labels) or "tag N" (first corner of a tag), else empty
};

struct Gathered {
  std::vector<Frame> frames;
  std::vector<calib::Correspondence> points;
  std::vector<Source> sources;
};

std::string prefixed(const std::string& name, std::size_t frame, std::size_t frames) {
  return frames > 1 ? "f" + std::to_string(frame + 1) + "/" + name : name;
}

// Frames `wanted` of a recording (a video file or an image sequence), read in order; also its
// frame rate (0 when it does not say).
std::vector<cv::Mat> readVideoFrames(const std::string& path, const std::vector<int>& wanted, double& fps) {
  overlay::VideoSource video(path, "--video " + path);
  fps = video.fps();
  const int last = *std::max_element(wanted.begin(), wanted.end());
  std::vector<cv::Mat> out(wanted.size());
  cv::Mat frame;
  for (int i = 0; i <= last; ++i) {
    if (!video.read(frame))
      throw UsageError("--frame " + std::to_string(last) + ": " + path + " has only " + std::to_string(i) + " readable frames");
    for (std::size_t k = 0; k < wanted.size(); ++k)
      if (wanted[k] == i) out[k] = frame.type() == CV_8UC3 ? frame.clone() : cv::Mat();
  }
  for (const cv::Mat& m : out)
    if (m.empty()) throw UsageError("--video " + path + ": frames are not 8-bit colour images");
  return out;
}

Gathered gather(const CalibArgs& a, const calib::Camera& cam, const std::optional<Model>& model) {
  // The pictures: image files, or frames of a video.
  std::vector<std::string> picture_names = a.images;
  std::vector<cv::Mat> video_pictures;
  std::vector<double> times = a.times;
  if (!a.video.empty()) {
    if (!a.images.empty()) throw UsageError("--video: give --image files or --video with --frame, not both");
    if (a.video_frames.empty()) throw UsageError("--video: say which frames with --frame N (repeat for several)");
    double fps = 0.0;
    video_pictures = readVideoFrames(a.video, a.video_frames, fps);
    for (int f : a.video_frames) picture_names.push_back(a.video + "#" + std::to_string(f));
    if (!a.state_log.empty() && times.empty()) {
      if (!(fps > 0.0)) throw UsageError("--video " + a.video + ": no frame rate: give each frame's time with --time");
      for (int f : a.video_frames) times.push_back(f / fps);
    }
  } else if (!a.video_frames.empty()) {
    throw UsageError("--frame: needs --video");
  }
  const std::size_t n = picture_names.empty() ? a.labels.size() : picture_names.size();
  if (n == 0) throw UsageError("give --image FRAME (with --tags and/or --labels) or --labels LABELS (see kccd calib --help)");
  if (!picture_names.empty() && !a.labels.empty() && a.labels.size() != picture_names.size())
    throw UsageError("--labels: given " + std::to_string(a.labels.size()) + " times for " + std::to_string(picture_names.size()) +
                     " images: give one labels file per --image, in the same order");
  if (!a.tags.empty() && picture_names.empty()) throw UsageError("--tags: needs --image (tags are detected in the images)");
  if (!picture_names.empty() && a.tags.empty() && a.labels.empty())
    throw UsageError("--image: give --tags LAYOUT and/or --labels LABELS to say what the image shows");
  if (!a.states.empty() && a.states.size() != 1 && a.states.size() != n)
    throw UsageError("--state: given " + std::to_string(a.states.size()) + " times for " + std::to_string(n) +
                     " frames: give it once (all frames) or once per frame");
  if (!a.states.empty() && !model) throw UsageError("--state: needs --model");
  if (!a.state_log.empty() && !model) throw UsageError("--states: needs --model");
  if (!a.state_log.empty() && !a.states.empty()) throw UsageError("--state and --states: give one of them");
  if (a.state_log.empty() != times.empty())
    throw UsageError(a.state_log.empty() ? "--time: needs --states LOG.csv" : "--states: give each frame's time with --time");
  if (!times.empty() && times.size() != n)
    throw UsageError("--time: given " + std::to_string(times.size()) + " times for " + std::to_string(n) + " frames: give one per frame");
  std::optional<StateLog> log;
  double max_gap = a.max_gap;
  if (!a.state_log.empty()) {
    log = loadStateLog(a.state_log, *model, splitCommas(a.ignore_columns));
    if (max_gap == 0.0) max_gap = 1.5 * log->medianPeriod();
  }

  std::optional<calib::TagLayout> layout;
  if (!a.tags.empty()) layout = calib::loadTagLayout(a.tags);
  Gathered g;
  g.frames.resize(n);
  for (std::size_t f = 0; f < n; ++f) {
    Frame& fr = g.frames[f];
    if (!a.states.empty()) {
      const std::string& text = a.states[a.states.size() == 1 ? 0 : f];
      fr.state = parseStateBox(*model, text, "", "", "", true).lower;
    } else if (log) {
      fr.state.assign(static_cast<std::size_t>(model->stateSize()), 0.0);
      if (stateAt(*log, times[f], max_gap, fr.state) == StateMatch::None)
        throw UsageError("--time " + format(times[f]) + ": " + a.state_log + " has no sample within --max-gap " + format(max_gap) +
                         " s of it (the log covers " + format(log->times.front()) + " ... " + format(log->times.back()) + " s)");
    }
    if (!picture_names.empty()) {
      fr.image = picture_names[f];
      fr.bgr = video_pictures.empty() ? calib::readImageFile(fr.image, calib::ImageColour::Bgr) : video_pictures[f];
      checkImageSize(fr.bgr, cam, fr.image, a.intrinsics);
      if (layout) {
        cv::Mat gray;
        cv::cvtColor(fr.bgr, gray, cv::COLOR_BGR2GRAY);
        const std::vector<calib::TagDetection> dets = calib::detectTags(gray);
        const calib::TagCorrespondences tc = calib::tagCorrespondences(dets, *layout, fr.image);
        fr.unknown_ids = tc.unknown_ids;
        for (std::size_t i = 0; i < tc.points.size(); ++i) {
          calib::Correspondence c = tc.points[i];
          const std::string tag_name = c.name.substr(0, c.name.find('.'));
          c.name = prefixed(c.name, f, n);
          g.points.push_back(c);
          g.sources.push_back({f, true, i % 4 == 0 ? prefixed(tag_name, f, n) : ""});
        }
        fr.tag_points = static_cast<int>(tc.points.size());
      }
    }
    if (!a.labels.empty()) {
      const calib::Labels labels = calib::loadLabels(a.labels[f]);
      for (const calib::Label& l : labels.labels) {
        cv::Point3d world;
        if (!l.bodyFixed()) {
          world = *l.world;
        } else if (!model) {
          throw UsageError(l.where + ": " + l.name + ": a body label needs --model (the model places its body)");
        } else if (l.state) {
          world = calib::worldPoint(*model, l);
        } else if (!a.states.empty() || log || model->stateSize() == 0) {
          world = calib::worldPoint(*model, l, fr.state);
        } else {
          throw UsageError(l.where + ": " + l.name + ": a body label needs a state: give state: [...] in the label or --state");
        }
        g.points.push_back({prefixed(l.name, f, n), l.pixel, world});
        g.sources.push_back({f, false, prefixed(l.name, f, n)});
      }
      fr.label_points = static_cast<int>(labels.labels.size());
    }
  }
  return g;
}

// The volumes of the model at `state` as a BGRA layer seen by the solved camera.
cv::Mat volumesLayer(const Model& m, const calib::Camera& cam, std::span<const double> state, const std::string& camera_name,
                     std::string& renderer_name) {
  Checker checker(m);
  const std::vector<double> s(state.begin(), state.end());
  const QueryResult& r = checker.query(s, s, QueryOptions{.type = QueryType::Distances});
  const std::vector<SafetyStatus> status = render::bodyStatus(m, r);
  const std::vector<render::Volume> volumes = render::staticSceneVolumes(m, checker, s, status);
  try {
    render::Renderer renderer(cam);
    render::Style style;
    style.labels = m.bodies.size() <= 12;  // names of many bodies only cover each other
    renderer_name = renderer.rendererString();
    return renderer.render(volumes, style, true, false).bgra;
  } catch (const calib::CameraError& e) {
    throw UsageError(camera_name + ": " + e.what());
  }
}

std::string checkPath(const std::string& path, std::size_t frame) {
  if (frame == 0) return path;
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + std::to_string(frame + 1) + p.extension().string())).string();
}

Exit runCalib(const CalibArgs& a) {
  {
    std::string ext = std::filesystem::path(a.output).extension().string();
    if (ext != ".yaml" && ext != ".yml") throw UsageError("-o " + a.output + ": the camera file must be a .yaml or .yml file");
    checkOutputPath(a.output, "-o", ext);
  }
  if (!a.check.empty()) checkOutputPath(a.check, "--check", ".png");
  const calib::Camera intrinsics = loadIntrinsics(a.intrinsics);
  std::optional<calib::Camera> truth;
  if (!a.truth.empty()) truth = calib::loadCamera(a.truth);
  std::optional<Model> model;
  if (!a.model.empty()) model = loadOrExplain(a.model);
  const Gathered g = gather(a, intrinsics, model);

  calib::PoseOptions options;
  options.ransac_threshold_px = a.threshold;
  options.min_inliers = a.min_inliers;
  const calib::PoseResult r = calib::solvePose(intrinsics, g.points, options);
  const bool solved = r.status == calib::PoseStatus::Solved;

  // The reprojection uncertainty of the model's volumes at the first frame's state.
  std::optional<double> volume_sigma;
  const std::vector<double>* state = nullptr;
  if (model && !g.frames.empty() && (static_cast<int>(g.frames[0].state.size()) == model->stateSize())) state = &g.frames[0].state;
  if (solved && model && state) volume_sigma = calib::projectedSigmaPx(r.camera, r.covariance, corePoints(*model, *state));

  // Against a known camera (synthetic recordings): the rotation and camera position errors.
  std::optional<std::pair<double, double>> truth_error;
  if (solved && truth) {
    cv::Matx33d ra, rb;
    cv::Rodrigues(r.camera.rvec, ra);
    cv::Rodrigues(truth->rvec, rb);
    const cv::Matx33d d = ra * rb.t();
    const double sin_half2 = 0.5 * std::hypot(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
    const double angle = std::atan2(sin_half2, 0.5 * (d(0, 0) + d(1, 1) + d(2, 2) - 1.0)) * 180.0 / CV_PI;
    const cv::Vec3d ca = -(ra.t() * r.camera.tvec), cb = -(rb.t() * truth->tvec);
    truth_error = std::make_pair(angle, cv::norm(ca - cb));
  }

  std::vector<int> unknown;
  for (const Frame& f : g.frames) unknown.insert(unknown.end(), f.unknown_ids.begin(), f.unknown_ids.end());
  std::sort(unknown.begin(), unknown.end());
  unknown.erase(std::unique(unknown.begin(), unknown.end()), unknown.end());

  std::string renderer_name;
  if (solved) {
    writeFileAtomically(a.output, calib::cameraText(r.camera));
    if (!a.check.empty()) {
      const cv::Matx33d k = r.camera.camera_matrix;
      std::vector<cv::Point3d> world;
      for (const auto& c : g.points) world.push_back(c.world);
      for (std::size_t f = 0; f < g.frames.size(); ++f) {
        std::vector<CheckPoint> pts;
        for (std::size_t i = 0; i < g.points.size(); ++i) {
          if (g.sources[i].frame != f) continue;
          CheckPoint p;
          p.pixel = g.points[i].pixel;
          p.residual_px = r.residuals[i].px;
          p.inlier = r.residuals[i].inlier;
          p.label = g.sources[i].label;
          const cv::Matx33d rot = [&] {
            cv::Matx33d m;
            cv::Rodrigues(r.camera.rvec, m);
            return m;
          }();
          const cv::Vec3d c = rot * cv::Vec3d(world[i].x, world[i].y, world[i].z) + r.camera.tvec;
          if (c[2] > 1e-9) {
            std::vector<cv::Point2d> proj;
            cv::projectPoints(std::vector<cv::Point3d>{world[i]}, r.camera.rvec, r.camera.tvec, k, r.camera.distortion, proj);
            p.projected = proj[0];
          } else {
            p.projected = cv::Point2d(std::nan(""), std::nan(""));
          }
          pts.push_back(p);
        }
        cv::Mat layer;
        if (model && static_cast<int>(g.frames[f].state.size()) == model->stateSize())
          layer = volumesLayer(*model, r.camera, g.frames[f].state, a.intrinsics, renderer_name);
        std::vector<std::string> head{
            "kccd calib: " + std::to_string(r.inliers) + " of " + std::to_string(g.points.size()) + " points agree, RMS " +
                num(*r.camera.reprojection_rms_px) + " px" +
                (g.frames.size() > 1 ? " (frame " + std::to_string(f + 1) + " of " + std::to_string(g.frames.size()) + ")" : ""),
            "1 sigma: rotation " + num(*r.camera.rotation_sigma_deg) + " deg, position " + num(*r.camera.position_sigma_m * 1000) +
                " mm" + (volume_sigma ? ", volumes " + num(*volume_sigma) + " px" : std::string()),
            "o seen  + projected  residual x" + num(a.magnify) + (r.rejected.empty() ? "" : "  red: rejected (to scale)")};
        const cv::Mat img = drawCheck(g.frames[f].bgr, {r.camera.width, r.camera.height}, layer, pts, head, a.magnify);
        writePngAtomically(checkPath(a.check, f), img, "--check");
      }
    }
  }

  if (a.json) {
    nlohmann::json j;
    j["status"] = calib::toString(r.status);
    j["message"] = r.message;
    j["points"] = g.points.size();
    j["inliers"] = r.inliers;
    j["rejected"] = r.rejected;
    j["unknown_tag_ids"] = unknown;
    j["residuals"] = nlohmann::json::array();
    for (std::size_t i = 0; i < r.residuals.size(); ++i)
      j["residuals"].push_back({{"name", r.residuals[i].name}, {"px", number(r.residuals[i].px)}, {"inlier", r.residuals[i].inlier}});
    j["frames"] = nlohmann::json::array();
    for (const Frame& f : g.frames)
      j["frames"].push_back({{"image", f.image}, {"tag_points", f.tag_points}, {"label_points", f.label_points}, {"unknown_tag_ids", f.unknown_ids}});
    if (solved) {
      j["output"] = a.output;
      j["reprojection_rms_px"] = *r.camera.reprojection_rms_px;
      j["rotation_sigma_deg"] = *r.camera.rotation_sigma_deg;
      j["position_sigma_m"] = *r.camera.position_sigma_m;
      j["volume_sigma_px"] = volume_sigma ? nlohmann::json(*volume_sigma) : nlohmann::json(nullptr);
      j["rvec"] = {r.camera.rvec[0], r.camera.rvec[1], r.camera.rvec[2]};
      j["tvec"] = {r.camera.tvec[0], r.camera.tvec[1], r.camera.tvec[2]};
      cv::Matx33d rot;
      cv::Rodrigues(r.camera.rvec, rot);
      const cv::Vec3d centre = -(rot.t() * r.camera.tvec);
      j["camera_position"] = {centre[0], centre[1], centre[2]};
      if (!a.check.empty()) j["check"] = a.check;
      if (!renderer_name.empty()) j["renderer"] = renderer_name;
      if (truth_error) j["truth_error"] = {{"rotation_deg", truth_error->first}, {"position_m", truth_error->second}};
    }
    std::cout << j.dump(2) << "\n";
  } else if (!a.quiet) {
    std::cout << (solved ? "" : "not solved: ") << r.message << "\n";
    if (truth_error)
      std::cout << "against " << a.truth << ": rotation " << num(truth_error->first) << " deg (" << num(truth_error->first / *r.camera.rotation_sigma_deg, 2)
                << " sigma), position " << num(truth_error->second * 1000) << " mm (" << num(truth_error->second / *r.camera.position_sigma_m, 2)
                << " sigma)\n";
    if (volume_sigma) std::cout << "model volumes at the state: +-" << num(*volume_sigma) << " px (1 sigma, worst core point)\n";
    if (!unknown.empty()) {
      std::cout << "tags not in the layout (ignored):";
      for (int id : unknown) std::cout << " " << id;
      std::cout << "\n";
    }
    if (solved) std::cout << "camera written to " << a.output << (a.check.empty() ? "" : ", check image " + a.check) << "\n";
  }
  if (!solved) {
    std::cerr << "kccd: calib: " << oneLine(r.message) << "\n";
    return Exit::NotSolvable;
  }
  return Exit::Ok;
}

// ---------------------------------------------------------------------------------------------
// kccd calib sheet

struct SheetArgs {
  std::string image, tags, model, camera, state, output, labels_template;
  int candidates = 40;
};

std::string yamlPixel(const cv::Point2d& p) { return "[" + format(p.x, 7) + ", " + format(p.y, 7) + "]"; }

Exit runSheet(const SheetArgs& a) {
  checkOutputPath(a.output, "-o", ".png");
  if (!a.labels_template.empty()) {
    const std::string ext = std::filesystem::path(a.labels_template).extension().string();
    if (ext != ".yaml" && ext != ".yml") throw UsageError("--template " + a.labels_template + ": must be a .yaml or .yml file");
    checkOutputPath(a.labels_template, "--template", ext);
  }
  if (!a.model.empty() && a.camera.empty())
    throw UsageError("--model: needs --camera (a camera file with a rough pose) to project the model's points");
  const cv::Mat bgr = calib::readImageFile(a.image, calib::ImageColour::Bgr);
  std::optional<calib::Camera> cam;
  if (!a.camera.empty()) {
    cam = calib::loadCamera(a.camera);
    checkImageSize(bgr, *cam, a.image, a.camera);
  }
  cv::Mat gray;
  cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
  const std::vector<calib::TagDetection> tags = calib::detectTags(gray);
  std::vector<bool> known(tags.size(), false);
  std::optional<calib::TagLayout> layout;
  if (!a.tags.empty()) {
    layout = calib::loadTagLayout(a.tags);
    calib::tagCorrespondences(tags, *layout, a.image);  // a tag seen twice is an error here too
    for (std::size_t i = 0; i < tags.size(); ++i) known[i] = layout->find(tags[i].id) != nullptr;
  }
  std::vector<SheetPoint> candidates;
  int n = 0;
  for (const cv::Point2d& p : candidateCorners(gray, tags, a.candidates)) candidates.push_back({"p" + std::to_string(++n), p});

  std::vector<SheetPoint> model_points;
  std::vector<double> state;
  std::optional<Model> model;
  if (!a.model.empty()) {
    model = loadOrExplain(a.model);
    if (model->stateSize() > 0) {
      if (a.state.empty()) throw UsageError("--model: give the robot's state in the image with --state");
      state = parseStateBox(*model, a.state, "", "", "", true).lower;
    }
    std::vector<std::string> names;
    const std::vector<cv::Point3d> world = corePoints(*model, state, &names);
    cv::Matx33d rot;
    cv::Rodrigues(cam->rvec, rot);
    for (std::size_t i = 0; i < world.size(); ++i) {
      const cv::Vec3d c = rot * cv::Vec3d(world[i].x, world[i].y, world[i].z) + cam->tvec;
      if (!(c[2] > 1e-6)) continue;
      std::vector<cv::Point2d> proj;
      cv::projectPoints(std::vector<cv::Point3d>{world[i]}, cam->rvec, cam->tvec, cam->camera_matrix, cam->distortion, proj);
      if (proj[0].x >= -0.5 && proj[0].y >= -0.5 && proj[0].x < bgr.cols - 0.5 && proj[0].y < bgr.rows - 0.5)
        model_points.push_back({names[i], proj[0]});
    }
  } else if (!a.state.empty()) {
    throw UsageError("--state: needs --model");
  }

  const cv::Mat sheet = drawSheet(bgr, tags, known, candidates, model_points);
  if (!a.labels_template.empty()) {
    std::string t = "# Labels for " + a.image +
                    " (made by kccd calib sheet; see the sheet image " + a.output + ").\n"
                    "# Uncomment the points you can identify, give each its world point (metres) or its body and\n"
                    "# point in the body frame, delete the rest, and pass the file to kccd calib --labels.\n"
                    "labels:\n";
    for (const SheetPoint& p : candidates) t += "#  - {name: " + p.name + ", pixel: " + yamlPixel(p.pixel) + ", world: [X, Y, Z]}\n";
    for (std::size_t i = 0; i < tags.size(); ++i) {
      if (known[i]) continue;  // --tags places these itself
      for (std::size_t k = 0; k < 4; ++k)
        t += "#  - {name: tag" + std::to_string(tags[i].id) + ".c" + std::to_string(k) + ", pixel: " + yamlPixel(tags[i].corners[k]) +
             ", world: [X, Y, Z]}\n";
    }
    if (model) {
      std::string st;
      for (double v : state) st += (st.empty() ? "" : ", ") + format(v, 10);
      for (const SheetPoint& p : model_points) {
        const std::string body = p.name.substr(0, p.name.rfind('.'));
        const std::size_t k = std::stoul(p.name.substr(p.name.rfind('.') + 1));
        const Body* b = nullptr;
        for (const Body& bb : model->bodies) b = bb.name == body ? &bb : b;
        const Vec3& q = b->points[k];
        auto xyz = [](const Vec3& v) { return "[" + format(v.x(), 10) + ", " + format(v.y(), 10) + ", " + format(v.z(), 10) + "]"; };
        // Points of world-fixed bodies are world points; the others are placed by the state.
        t += "#  - {name: " + p.name + ", pixel: " + yamlPixel(p.pixel) +
             (b->frame == kWorld ? ", world: " + xyz(q)
                                 : ", body: " + body + ", point: " + xyz(q) + (state.empty() ? "" : ", state: [" + st + "]")) +
             "}  # projected: click the real point\n";
      }
    }
    writeFileAtomically(a.labels_template, t);
  }
  writePngAtomically(a.output, sheet, "-o");
  std::cout << "sheet " << a.output << ": " << tags.size() << " tag" << (tags.size() == 1 ? "" : "s") << " detected";
  int unknown = 0;
  for (bool k : known) unknown += k ? 0 : 1;
  if (layout && unknown > 0) std::cout << " (" << unknown << " not in the layout)";
  std::cout << ", " << candidates.size() << " candidate points" << (model ? ", " + std::to_string(model_points.size()) + " model points" : "")
            << (a.labels_template.empty() ? "" : "; template " + a.labels_template) << "\n";
  return Exit::Ok;
}

}  // namespace

Runner addCalib(CLI::App& app) {
  CLI::App* sub = app.add_subcommand(
      "calib",
      "Solve the camera's pose in the world from AprilTags and labelled points, with its quality.\n"
      "Tags: every corner of a detected tag36h11 tag that the layout (--tags) places is a point.\n"
      "Labels (--labels): pixels of known world points, or of points on a model body placed by a state.\n"
      "Several frames (--image repeated, one --labels each) add points seen with the robot elsewhere.\n"
      "Exit 0 solved (camera file written), 2 bad input, 4 not solvable (the message says what to add).");
  sub->require_subcommand(0, 1);
  auto a = std::make_shared<CalibArgs>();
  sub->add_option("--intrinsics", a->intrinsics, "Camera file with the intrinsics and lens distortion (its pose is ignored); required");
  sub->add_option("--image", a->images, "A frame from the fixed camera (repeat for several frames)")->allow_extra_args(false);
  sub->add_option("--video", a->video,
                  "A recording from the fixed camera (a video file or an image sequence such as frames/frame_%06d.png, "
                  "as kccd overlay reads): its frames given by --frame are the frames");
  sub->add_option("--frame", a->video_frames, "Frame index in --video (from 0; repeat for several frames)")
      ->allow_extra_args(false)
      ->check(CLI::Range(0, 100000000));
  sub->add_option("--tags", a->tags, "Tag layout: where the AprilTags are in the world");
  sub->add_option("--labels", a->labels, "Labelled points (repeat: one file per --image, same order)")->allow_extra_args(false);
  sub->add_option("--model", a->model, "Model file placing the body labels (and drawn in the check image)");
  sub->add_option("--state", a->states,
                  "The robot's state in the frames (comma-separated; once for all frames, or once per frame) for body labels "
                  "without their own state, and for the check image")
      ->allow_extra_args(false);
  sub->add_option("--states", a->state_log,
                  "State log (CSV: time and one column per state value, see kccd info) placing the body labels at each frame's --time");
  sub->add_option("--time", a->times, "Each frame's time in the state log's clock (s; once per frame; with --video default frame / fps)")
      ->allow_extra_args(false)
      ->check(finiteIn(-1e300, 1e300));
  sub->add_option("--max-gap", a->max_gap, "No state when the log has no sample this close (s; default 1.5 x its median period)")
      ->check(finiteIn(0, 1e300));
  sub->add_option("--ignore-columns", a->ignore_columns, "Comma-separated state log columns to skip (an unknown column is an error)");
  sub->add_option("-o,--output", a->output, "Camera file to write (intrinsics, pose, quality); written only when solved; required");
  sub->add_option("--check", a->check,
                  "Check image (.png): the frame, the model at the state, every point seen (o), projected (+) and its residual "
                  "magnified; with several frames also NAME_2.png, ...");
  sub->add_option("--truth", a->truth, "A known camera file (e.g. from kccd synth): also report the error against it");
  sub->add_option("--threshold", a->threshold, "RANSAC: a point farther than this from its projection is rejected (px)")
      ->check(finiteIn(0.1, 1000))
      ->capture_default_str();
  sub->add_option("--min-inliers", a->min_inliers, "Fewer agreeing points: not solvable")
      ->check(CLI::Range(4, 1000000))
      ->capture_default_str();
  sub->add_option("--magnify", a->magnify, "Residual vectors in the check image are drawn this many times longer")
      ->check(finiteIn(1, 1000))
      ->capture_default_str();
  sub->add_flag("--json", a->json, "Print the result as JSON (status, sigmas, rejected, residuals)");
  sub->add_flag("-q,--quiet", a->quiet, "Print nothing but errors");

  CLI::App* sheet = sub->add_subcommand(
      "sheet",
      "A labelling aid: the frame with detected tags (ids, corner order 0..3), numbered candidate points and, with --model\n"
      "and a camera with a rough pose, the model's core points projected; --template writes a labels file to fill in.");
  auto s = std::make_shared<SheetArgs>();
  sheet->add_option("--image", s->image, "The frame")->required();
  sheet->add_option("--tags", s->tags, "Tag layout: tags it places are drawn green, others orange");
  sheet->add_option("--model", s->model, "Model whose core points are projected (needs --camera and --state)");
  sheet->add_option("--camera", s->camera, "Camera file with a rough pose (e.g. from an earlier solve)");
  sheet->add_option("--state", s->state, "The robot's state in the frame (comma-separated)");
  sheet->add_option("--candidates", s->candidates, "Most candidate points to number")->check(CLI::Range(0, 1000))->capture_default_str();
  sheet->add_option("-o,--output", s->output, "Sheet image (.png)")->required();
  sheet->add_option("--template", s->labels_template, "Labels file (.yaml) to fill in: every candidate, commented out");

  const Runner intrinsics = addCalibIntrinsics(*sub);
  CLI::App* intrinsics_sub = sub->get_subcommand("intrinsics");

  return [sheet, a, s, intrinsics, intrinsics_sub]() -> Exit {
    if (sheet->parsed()) return runSheet(*s);
    if (intrinsics_sub->parsed()) return intrinsics();
    if (a->intrinsics.empty()) throw UsageError("calib: --intrinsics CAMERA.yaml is required (see kccd calib --help)");
    if (a->output.empty()) throw UsageError("calib: -o CAMERA.yaml is required (see kccd calib --help)");
    return runCalib(*a);
  };
}

}  // namespace kccd::cli
