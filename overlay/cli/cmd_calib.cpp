// `kccd calib`: the camera's pose in the world from AprilTags and labelled points in one or more
// frames, with its quality and a check image. The options become kccd::overlay's gathering inputs;
// the gathering, the solve and the check images are library calls. `calib sheet` and `calib
// intrinsics` are in their own files.
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "calib_frames.hpp"
#include "cli_args.hpp"
#include "cli_files.hpp"
#include "cli_model.hpp"
#include "cli_output.hpp"
#include "commands.hpp"
#include "kccd/overlay/calibration/calib_check.hpp"
#include "kccd/overlay/calibration/calib_gather.hpp"
#include "kccd/overlay/calibration/calib_refine.hpp"
#include "kccd/overlay/calibration/calib_report.hpp"
#include "kccd/overlay/calibration/calib_solve.hpp"
#include "kccd/render/model_view.hpp"
#include "kccd/state_log.hpp"

namespace kccd::cli {
namespace {

struct CalibArgs : FrameOptions {
  std::string intrinsics, tags, model, output, check, truth, rough_camera, mask_bodies, refine, draw = "auto";
  std::string camera_frame;  ///< a camera fixed to this frame of the model (a wrist or head camera)
  std::vector<std::string> labels, masks;
  double threshold = 8.0, magnify = 20.0;
  int min_inliers = 6;
  bool json = false, quiet = false;
};

// Body labels need --model, and a state (in the label, or from --state or --states): said with
// the options before any picture is read.
void checkBodyLabels(const calib::Labels& labels, const std::optional<Model>& model, bool frame_state) {
  for (const calib::Label& l : labels.labels) {
    if (!l.bodyFixed()) continue;
    if (!model) throw UsageError(l.where + ": " + l.name + ": a body label needs --model (the model places its body)");
    if (!l.state && !frame_state && model->stateSize() != 0)
      throw UsageError(l.where + ": " + l.name +
                       ": a body label needs a state: give state: [...] in the label or --state");
  }
}

bool autoMasks(const CalibArgs& a) { return a.masks.size() == 1 && a.masks.front() == "auto"; }

// The gathering inputs the options describe: the frames (calib_frames.hpp), the labels and the
// tag layout; with --masks auto, frames spread over the recording into `recording`.
overlay::GatherInputs gatherInputs(const CalibArgs& a, const calib::Camera& cam, const std::optional<Model>& model,
                                   std::vector<overlay::RecordingSample>& recording) {
  FrameOptions frames = a;
  if (autoMasks(a)) frames.recording_samples = 40;
  GivenFrames given =
      givenFrames(frames, a.labels.size(), !a.tags.empty(), model, !a.masks.empty() || a.refine == "edges");
  recording = std::move(given.recording);
  for (const std::string& w : given.warnings) std::cerr << "kccd calib: warning: " << w << "\n";
  overlay::GatherInputs in;
  in.camera = cam;
  in.camera_name = a.intrinsics;
  in.model = model ? &*model : nullptr;
  if (!a.tags.empty()) in.tags = calib::loadTagLayout(a.tags);
  in.frames.resize(given.count);
  for (std::size_t f = 0; f < given.count; ++f) {
    overlay::CalibFrame& fr = in.frames[f];
    fr.state = given.states[f];
    if (!given.names.empty()) fr.image = given.names[f];
    if (!given.pictures.empty()) fr.bgr = given.pictures[f];
    if (!a.labels.empty() && a.labels[f] != "none") {
      fr.labels = calib::loadLabels(a.labels[f]);
      checkBodyLabels(*fr.labels, model, fr.state.has_value());
    }
  }
  return in;
}

// What the pose is refined to: the masks (read and checked before anything else is) or the
// pictures' edges, the bodies they show and a rough start.
std::optional<overlay::RefineInputs> refineInputs(const CalibArgs& a, const calib::Camera& cam,
                                                  const std::optional<Model>& model) {
  const bool edges = a.refine == "edges";
  if (edges && !a.masks.empty())
    throw UsageError("--refine edges: refines to the pictures themselves; --masks goes with --refine masks");
  if (a.refine == "masks" && a.masks.empty())
    throw UsageError("--refine masks: give the masks with --masks M1.png ...");
  if (a.masks.empty() && !edges) {
    if (!a.rough_camera.empty()) throw UsageError("--camera: a start for --masks or --refine edges (give one)");
    if (!a.mask_bodies.empty()) throw UsageError("--mask-bodies: goes with --masks or --refine edges");
    return std::nullopt;
  }
  if (!model)
    throw UsageError(edges ? "--refine edges: needs --model (the robot drawn to match the pictures)"
                           : "--masks: needs --model (the robot drawn to match the masks)");
  overlay::RefineInputs in;
  in.spell = [](const std::string& field) { return optionSpelling(field); };
  if (edges) in.source = calib::RefineSource::Edges;
  in.draw = a.draw;
  for (const std::string& m : a.masks) {
    if (autoMasks(a)) break;
    if (m == "auto")
      throw UsageError("--masks auto: makes every frame's mask from the recording: give it alone, not with mask files");
    in.masks.push_back(calib::readMask(m, cam.width, cam.height));
    in.mask_names.push_back(m);
  }
  if (!a.mask_bodies.empty()) {
    std::stringstream list(a.mask_bodies);
    for (std::string name; std::getline(list, name, ',');) {
      const int b = model->bodyIndex(name);
      if (b < 0)
        throw UsageError("--mask-bodies: '" + name + "' is not a body of " + a.model + " (kccd info lists them)");
      in.bodies.push_back(b);
    }
  }
  if (!a.rough_camera.empty()) in.rough = calib::loadCamera(a.rough_camera);
  return in;
}

// The check image of frame `frame` (from 0): the --check path, then NAME_2.png, ...
std::string checkPath(const std::string& path, std::size_t frame) {
  if (frame == 0) return path;
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + std::to_string(frame + 1) + p.extension().string())).string();
}

Exit runCalib(const CalibArgs& a) {
  const std::string ext = std::filesystem::path(a.output).extension().string();
  if (ext != ".yaml" && ext != ".yml")
    throw UsageError("-o " + a.output + ": the camera file must be a .yaml or .yml file");
  checkOutputPath(a.output, "-o", ext);
  if (!a.check.empty()) checkOutputPath(a.check, "--check", ".png");
  const calib::Camera intrinsics = overlay::intrinsicsOf(calib::loadCamera(a.intrinsics, calib::CameraPose::Optional));
  std::optional<calib::Camera> truth;
  if (!a.truth.empty()) truth = calib::loadCamera(a.truth);
  std::optional<Model> model;
  if (!a.model.empty()) model = loadOrExplain(a.model);
  std::optional<overlay::RefineInputs> refine_inputs = refineInputs(a, intrinsics, model);
  std::vector<overlay::RecordingSample> recording;
  if (!a.camera_frame.empty()) {
    if (!model) throw UsageError("--camera-frame: needs --model (the robot the camera is fixed to)");
    if (refine_inputs)
      throw UsageError("--camera-frame: not with --masks or --refine (they refine a camera fixed in the world)");
    calib::Camera mount;
    mount.frame = a.camera_frame;
    render::cameraFrame(*model, mount, "--camera-frame");  // a frame of the model, before any picture is read
  }
  overlay::Gathered g = overlay::gatherCorrespondences(gatherInputs(a, intrinsics, model, recording));
  if (refine_inputs) refine_inputs->recording = std::move(recording);
  if (!a.camera_frame.empty()) {
    calib::Camera mount;
    mount.frame = a.camera_frame;
    // Every point in the mount's frame at its frame's state: the pose solved is mount -> camera.
    g = overlay::inMountFrame(std::move(g), *model, render::cameraFrame(*model, mount, "--camera-frame"),
                              "--camera-frame " + a.camera_frame);
  }

  calib::PoseOptions options;
  options.ransac_threshold_px = a.threshold;
  options.min_inliers = a.min_inliers;
  // The model's uncertainty figure places its points in the world: not for a camera on the robot.
  overlay::CalibSolution s = overlay::solveCalibration(
      intrinsics, g, options, model && a.camera_frame.empty() ? &*model : nullptr, truth ? &*truth : nullptr);
  s.pose.camera.frame = a.camera_frame;
  std::optional<overlay::Refinement> refinement;
  if (refine_inputs) {
    refinement = overlay::refineCalibration(s, g, intrinsics, *model, *refine_inputs, truth ? &*truth : nullptr);
    if (!refinement->result.improved && !s.solved())
      s.pose.message = refinement->result.message + " and the points do not solve (" + s.pose.message +
                       "): add labels of the robot or tags, or start from --camera ROUGH.yaml";
  }
  const calib::PoseResult& r = s.pose;
  std::string renderer_name;
  if (s.solved()) {
    writeFileAtomically(
        a.output, calib::cameraText(r.camera) + (refinement ? overlay::refinementText(*refinement) : std::string()));
    for (std::size_t f = 0; !a.check.empty() && f < g.frames.size(); ++f) {
      overlay::CheckImage check =
          overlay::checkImage(g, s, f, model ? &*model : nullptr,
                              {.magnify = a.magnify,
                               .camera_name = a.intrinsics,
                               .pose_source = a.refine == "edges" ? "the pictures' edges" : "the robot's masks"});
      if (!check.renderer.empty()) renderer_name = check.renderer;
      if (refinement)
        overlay::drawMaskAgreement(
            check.bgr, r.camera,
            !refinement->masks.empty()     ? refinement->masks[f]
            : refine_inputs->masks.empty() ? cv::Mat()
                                           : refine_inputs->masks[f],
            calib::placeVolumes(*model, g.frames[f].state, refinement->bodies),
            f < refinement->meshes.size() ? refinement->meshes[f] : std::vector<calib::PlacedMesh>{});
      writePngAtomically(checkPath(a.check, f), check.bgr, "--check");
    }
  }

  if (a.json) {
    nlohmann::json report =
        overlay::calibReport(g, s, {.camera = a.output, .check = a.check, .renderer = renderer_name});
    if (refinement) report["refinement"] = overlay::refinementJson(*refinement);
    std::cout << report.dump(2) << "\n";
  } else if (!a.quiet) {
    if (refinement) {
      for (std::size_t f = 0; f < refinement->result.frames.size(); ++f) {
        const calib::FrameAgreement& fa = refinement->result.frames[f];
        if (refinement->result.source == calib::RefineSource::Edges) {
          std::cout << "frame " << f + 1 << ": outline on edges " << format(100 * fa.matched_before, 3) << "%";
          if (refinement->result.improved) std::cout << " -> " << format(100 * fa.matched_after, 3) << "%";
        } else {
          std::cout << (autoMasks(a) ? "frame " + std::to_string(f + 1) + " (mask from the recording)"
                                     : "mask " + a.masks[f])
                    << ": IoU " << format(fa.iou_before, 4);
          if (refinement->result.improved) std::cout << " -> " << format(fa.iou_after, 4);
        }
        std::cout << ", outline " << format(fa.rms_px, 3) << " px rms over " << fa.outline_points << " points"
                  << (refinement->result.improved ? "" : " (the start, kept)") << "\n";
      }
      if (!refinement->masks_from.empty()) std::cout << refinement->masks_from << "\n";
      if (!refinement->result.improved && s.solved()) std::cout << refinement->result.message << "\n";
    }
    std::cout << (s.solved() ? "" : "not solved: ") << r.message << "\n";
    if (s.truth_error)
      std::cout << "against " << a.truth << ": rotation " << format(s.truth_error->rotation_deg, 3) << " deg ("
                << format(s.truth_error->rotation_deg / *r.camera.rotation_sigma_deg, 2) << " sigma), position "
                << format(s.truth_error->position_m * 1000, 3) << " mm ("
                << format(s.truth_error->position_m / *r.camera.position_sigma_m, 2) << " sigma)\n";
    if (s.volume_sigma_px)
      std::cout << "model volumes at the state: +-" << format(*s.volume_sigma_px, 3)
                << " px (1 sigma, worst core point)\n";
    if (!g.unknown_tag_ids.empty()) {
      std::cout << "tags not in the layout (ignored):";
      for (int id : g.unknown_tag_ids) std::cout << " " << id;
      std::cout << "\n";
    }
    if (s.solved())
      std::cout << "camera written to " << a.output << (a.check.empty() ? "" : ", check image " + a.check) << "\n";
  }
  if (!s.solved()) {
    std::cerr << "kccd: calib: " << oneLine(r.message) << "\n";
    return Exit::NotSolvable;
  }
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
  sub->add_option("--intrinsics", a->intrinsics,
                  "Camera file with the intrinsics and lens distortion (its pose is ignored); required");
  sub->add_option("--image", a->images, "A frame from the fixed camera (repeat for several frames)")
      ->allow_extra_args(false);
  sub->add_option("--video", a->video,
                  "A recording from the fixed camera (a video file or an image sequence such as frames/frame_%06d.png, "
                  "as kccd overlay reads): its frames given by --frame are the frames");
  sub->add_option("--frame", a->video_frames, "Frame index in --video or --bag (from 0; repeat for several frames)")
      ->allow_extra_args(false)
      ->check(CLI::Range(0, 100000000));
  addBagOptions(*sub, *a);
  sub->add_option("--tags", a->tags, "Tag layout: where the AprilTags are in the world");
  sub->add_option(
         "--labels", a->labels,
         "Labelled points (repeat: one file per --image, same order; none for a frame without labels, e.g. 4 labels on "
         "one frame and the others used by --masks or --refine edges only)")
      ->allow_extra_args(false);
  sub->add_option("--model", a->model, "Model file placing the body labels (and drawn in the check image)");
  sub->add_option("--camera-frame", a->camera_frame,
                  "The camera is fixed to this joint, body or link of --model (a wrist or head camera): every "
                  "frame's points are placed in that frame at the frame's state (--state, --states or --bag), the pose "
                  "solved is that frame -> camera, and the camera file says frame: NAME");
  sub->add_option(
         "--state", a->states,
         "The robot's state in the frames (comma-separated; once for all frames, or once per frame) for body labels "
         "without their own state, and for the check image")
      ->allow_extra_args(false);
  sub->add_option("--states", a->state_log,
                  "State log (CSV: time and one column per state value, see kccd info) placing the body labels at each "
                  "frame's --time");
  sub->add_option("--time", a->times,
                  "Each frame's time in the state log's clock (s; once per frame; with --video default frame / fps)")
      ->allow_extra_args(false)
      ->check(finiteIn(-1e300, 1e300));
  sub->add_option("--max-gap", a->max_gap,
                  "No state when the log has no sample this close (s; default 1.5 x its median period)")
      ->check(finiteIn(0, 1e300));
  sub->add_option("--ignore-columns", a->ignore_columns,
                  "Comma-separated state log columns to skip (an unknown column is an error)");
  sub->add_option("-o,--output", a->output,
                  "Camera file to write (intrinsics, pose, quality); written only when solved; required");
  sub->add_option(
      "--check", a->check,
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
  sub->add_option(
         "--masks", a->masks,
         "Robot masks, one per frame in the same order (PNG or any image; non-zero = robot, e.g. a segmentation "
         "tool's output): the pose is refined so the model's drawn robot matches them over all frames; needs "
         "--model and each frame's state. --masks auto: made from the recording itself (--video with --states, or "
         "--bag; a fixed camera): the robot is what differs from the background, estimated over 40 frames spread over "
         "the recording (at frame / fps on the log's clock, shifted as the first --time says when given), each pixel "
         "from "
         "the frames in which the drawn robot is away from it; people moving, lighting "
         "changes and the robot's shadows are foreground too")
      ->expected(1, -1);
  sub->add_option("--refine", a->refine,
                  "What the pose is refined to: masks (the default with --masks) or edges (no masks: the robot's drawn "
                  "outline is "
                  "pulled onto the pictures' own edges of its direction, coarse to fine; needs --model, each frame's "
                  "picture and "
                  "state, and a start a few degrees off at most, e.g. from 4 rough labels)")
      ->check(CLI::IsMember({"masks", "edges"}));
  sub->add_option("--draw", a->draw,
                  "What --masks or --refine edges draws of the robot: auto (the model's visuals, what the robot looks "
                  "like, when "
                  "it has them and they can be read; else its collision volumes), visuals, or volumes")
      ->check(CLI::IsMember({"auto", "visuals", "volumes"}))
      ->capture_default_str();
  sub->add_option("--camera", a->rough_camera,
                  "A rough camera file to start --masks or --refine edges from when no labels or tags give a start "
                  "(its pose is used)");
  sub->add_option("--mask-bodies", a->mask_bodies,
                  "Comma-separated bodies of the model that the masks (or, with --refine edges, the pictures) show "
                  "(default: all bodies)");
  sub->add_flag("--json", a->json, "Print the result as JSON (status, sigmas, rejected, residuals)");
  sub->add_flag("-q,--quiet", a->quiet, "Print nothing but errors");

  const Runner sheet = addCalibSheet(*sub);
  CLI::App* sheet_sub = sub->get_subcommand("sheet");
  const Runner intrinsics = addCalibIntrinsics(*sub);
  CLI::App* intrinsics_sub = sub->get_subcommand("intrinsics");
  const Runner label = addCalibLabel(*sub);
  CLI::App* label_sub = sub->get_subcommand("label");

  return [a, sheet, sheet_sub, intrinsics, intrinsics_sub, label, label_sub]() -> Exit {
    if (sheet_sub->parsed()) return sheet();
    if (intrinsics_sub->parsed()) return intrinsics();
    if (label_sub->parsed()) return label();
    if (a->intrinsics.empty()) throw UsageError("calib: --intrinsics CAMERA.yaml is required (see kccd calib --help)");
    if (a->output.empty()) throw UsageError("calib: -o CAMERA.yaml is required (see kccd calib --help)");
    return runCalib(*a);
  };
}

}  // namespace kccd::cli
