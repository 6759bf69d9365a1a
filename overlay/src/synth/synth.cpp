// A synthetic recording with ground truth (kccd/overlay/synth/synth.hpp): the options checked, then the
// motion (synth_trajectory), the scene (synth_scene), the frames through the sensor model
// (synth_sensor) and the truth (synth_truth), and on request the recording as a bag, its samples and
// frames (bags/state_log_bag), all written into a staged folder that is renamed into place when
// complete.
#include "kccd/overlay/synth/synth.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "kccd/calib/camera.hpp"
#include "kccd/overlay/bags/state_log_bag.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/synth/synth_scene.hpp"
#include "kccd/overlay/synth/synth_sensor.hpp"
#include "kccd/overlay/synth/synth_trajectory.hpp"
#include "kccd/overlay/synth/synth_truth.hpp"
#include "kccd/render/visuals.hpp"
#include "kccd/safety_status.hpp"

namespace kccd::overlay {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
constexpr char kBagFile[] = "states.mcap";

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// An error about one of the options' fields (a front end names it in its own spelling).
SynthError fieldError(const std::string& field, const std::string& problem) {
  return SynthError(InputLocation{{}, 0, 0, field}, problem);
}

// A number option within [lo, hi] (NaN refused).
void checkRange(double value, double lo, double hi, const char* field) {
  if (const std::optional<std::string> wrong = rangeProblem(value, lo, hi)) throw fieldError(field, *wrong);
}

// Every option that does not need the model's motion, in the order `kccd synth` has always checked
// them (the command line checks most ranges before): the first problem is the one reported.
void checkOptions(const SynthOptions& o, const Model& m) {
  if (m.bodies.size() > 255) throw SynthError(o.model + ": more than 255 bodies do not fit an 8-bit mask");
  videoFormat(o.codec);
  if (!(o.fps >= 1 && o.fps <= 240)) throw fieldError("fps", "must be 1 ... 240");
  checkRange(o.seconds, 0.04, 600, "seconds");
  if (std::floor(o.seconds * o.fps) < 1) throw fieldError("seconds", "too short for one frame at the frame rate");
  if (!(o.log_rate > 0) || std::abs(o.log_rate - o.fps) < 1e-9)
    throw fieldError("log_rate", "must differ from the frame rate (a real log runs on its own clock)");
  checkRange(o.log_rate, 1, 10000, "log_rate");
  checkRange(o.time_offset, 0, 10, "time_offset");
  checkRange(o.blur, 0, 10, "blur");
  checkRange(o.noise, 0, 50, "noise");
  if (o.visible_scale) checkRange(*o.visible_scale, 0.1, 0.95, "visible_scale");
  const fs::path out = fs::path(o.output).lexically_normal();
  if (out.empty() || out.filename().empty() || out.filename() == "." || out.filename() == "..")
    throw SynthError(spelledField(o.spell, "output") + " " + o.output + ": give a folder name");
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec))
    throw SynthError(spelledField(o.spell, "output") + " " + o.output + ": folder " + parent.string() +
                     " does not exist");
  if (fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec)) && !o.replace)
    throw SynthError(spelledField(o.spell, "output") + " " + o.output + ": exists and is not an empty folder (" +
                     spelledField(o.spell, "replace") + " replaces it)");
}

// The robot's appearance: its visual meshes (the model's visuals:) or shrunken SSCHs.
std::vector<render::LoadedVisual> appearanceOf(const SynthOptions& o, const Model& m) {
  const bool use_visuals =
      o.appearance == SynthAppearance::Visuals || (o.appearance == SynthAppearance::Auto && !m.visuals.empty());
  if (use_visuals && m.visuals.empty()) throw fieldError("appearance", "visuals: " + o.model + " has no visuals:");
  if (use_visuals && m.visuals.size() > 255)
    throw SynthError(o.model + ": " + std::to_string(m.visuals.size()) + " visuals: at most 255 can be drawn");
  if (use_visuals && o.visible_scale) throw fieldError("visible_scale", "applies to the appearance volumes only");
  return use_visuals ? render::loadVisuals(m) : std::vector<render::LoadedVisual>{};
}

}  // namespace

SynthResult synthesizeRecording(const SynthOptions& o, const SynthProgress& progress) {
  const auto t_start = Clock::now();
  const Model m = loadModel(o.model);
  checkOptions(o, m);
  const VideoFormat format = videoFormat(o.codec);
  const fs::path out = fs::path(o.output).lexically_normal();

  // The camera (given, or placed after the trajectory is known).
  std::optional<calib::Camera> given;
  const int width = o.width.value_or(SynthOptions::kDefaultWidth);
  const int height = o.height.value_or(SynthOptions::kDefaultHeight);
  if (!o.camera.empty()) {
    if (o.width || o.height)
      throw fieldError(o.width ? "width" : "height",
                       "shapes the default camera; the camera file " + o.camera + " fixes the size");
    given = calib::loadCamera(o.camera);
    if (!given->frame.empty())
      throw SynthError(o.camera + ": frame: synth films with a camera fixed in the world (this one is fixed to " +
                       printable(given->frame, 60) + ")");
  } else if (width < 64 || height < 64 || width > 4096 || height > 4096) {
    throw fieldError(width < 64 || width > 4096 ? "width" : "height", "must be 64 ... 4096 pixels");
  }

  const int frames = static_cast<int>(std::floor(o.seconds * o.fps + 1e-9));
  const SynthMotion motion = searchMotion(m,
                                          TrajectorySearch{.model = o.model,
                                                           .seconds = o.seconds,
                                                           .fps = o.fps,
                                                           .seed = o.seed,
                                                           .collision = o.collision,
                                                           .spell = o.spell},
                                          frames, o.log_rate, o.time_offset);
  const auto t_traj = Clock::now();

  SynthScene scene;
  scene.box = robotBox(m, motion.log);
  scene.camera = given ? *given : defaultCamera(scene.box, width, height);
  scene.room = makeRoom(scene.box, scene.camera.worldToCamera().inverse().translation());

  // The painter: the visible geometry, shaded, with its label mask.
  std::optional<FramePainter> painter;
  try {
    painter.emplace(m, scene.camera);
  } catch (const calib::CameraError& e) {
    throw SynthError(e.messageFrom(o.camera.empty() ? std::string("camera") : o.camera));
  }
  std::vector<render::LoadedVisual> visuals = appearanceOf(o, m);
  const bool use_visuals = !visuals.empty();
  painter->setAppearance(std::move(visuals), o.visible_scale.value_or(SynthOptions::kDefaultVisibleScale));

  // Tags: visible in the first frame around the robot's full volumes.
  scene.layout = makeTags(scene.room, scene.box, scene.camera, painter->fullMask(motion.states[0]), scene.visible_tags);
  if (scene.layout.tags.size() < 4)
    throw SynthError("camera: it sees fewer than 4 whole tags of the synthetic room (" +
                     std::to_string(scene.layout.tags.size()) + "); point it at the robot from farther away");

  // The static background: floor, walls, tags, light.
  const cv::Mat background = renderRoom(scene.camera, scene.layout, scene.room, o.seed);
  const auto t_bg = Clock::now();

  // Output folder, staged: an existing one is replaced only when the new one is complete.
  StagedOutput staged(out, StagedOutput::Kind::Folder, spelledField(o.spell, "output") + " " + o.output,
                      StagedOutput::Existing::ReplaceFolder);
  const fs::path dir = staged.path();
  const fs::path mask_dir = dir / "masks";
  fs::create_directory(mask_dir);
  std::optional<VideoFileWriter> video;
  try {
    video.emplace((dir / format.file).string(), format.fourcc, o.fps, scene.camera.width, scene.camera.height);
  } catch (const VideoFileError& e) {
    throw fieldError("codec", o.codec + ": this video cannot be written here (" + e.what() + ")");
  }

  SynthRun run;
  run.video_file = format.file;
  if (o.bag) run.bag_file = kBagFile;
  run.visuals = use_visuals;
  run.supersample = painter->renderOptions().supersample;
  run.mask_supersample = painter->renderOptions().mask_supersample;
  // The bag: the state log's samples, and each frame as the video gets it, stamped at its log time
  // (a robot's log has the camera and the joints on one clock: no offset to find).
  std::optional<StateLogBagWriter> bag;
  if (o.bag)
    bag.emplace(motion.log, dir / run.bag_file,
                StateLogBagOptions{.label = spelledField(o.spell, "output") + " " + o.output + ": " + run.bag_file});
  int written = 0;
  {
    SensorWriter writer(*video, mask_dir.string(), o.blur, o.noise, o.seed);
    writer.setVignette(vignetteGain(scene.camera));
    if (bag)
      writer.setFrameSink([&bag, &o](int i, const cv::Mat& frame) { bag->addImage(i / o.fps + o.time_offset, frame); });
    for (int i = 0; i < frames; ++i) {
      const auto r0 = Clock::now();
      cv::Mat mask;
      cv::Mat frame = painter->draw(background, motion.states[i], mask);
      run.render_s += seconds(r0, Clock::now());
      writer.push(i, std::move(frame), std::move(mask));
      if (progress) progress(static_cast<double>(i + 1) / frames);
    }
    writer.finish();
    if (!writer.error().empty())
      throw SynthError(spelledField(o.spell, "output") + " " + o.output + ": " + writer.error());
    written = writer.written();
    run.writer_s = writer.stageSeconds();
  }
  try {
    video->finish();
  } catch (const VideoFileError& e) {
    throw SynthError(spelledField(o.spell, "output") + " " + o.output + ": " + format.file + ": " + e.what());
  }
  if (written != frames)
    throw std::runtime_error("synth: wrote " + std::to_string(written) + " of " + std::to_string(frames) + " frames");

  if (bag) bag->finish();  // the samples after the last frame

  // Text outputs, then the truth.
  writeRecordingFiles(dir, motion, scene);
  const auto t_end = Clock::now();
  run.renderer = painter->rendererString();
  run.total_s = seconds(t_start, t_end);
  run.trajectory_s = seconds(t_start, t_traj);
  run.background_s = seconds(t_traj, t_bg);
  writeFileAtomically(dir / "synth.json", truthText(o, m, motion, scene, run));
  staged.commit();  // into place

  SynthResult r;
  r.folder = o.output;
  r.video_file = format.file;
  r.bag_file = run.bag_file;
  r.frames = frames;
  r.width = scene.camera.width, r.height = scene.camera.height;
  r.fps = o.fps, r.log_rate = o.log_rate, r.time_offset = o.time_offset;
  r.log_rows = motion.log.rows();
  r.tags = scene.layout.tags.size();
  r.visuals = use_visuals;
  r.min_distance = motion.min_distance;
  for (int i = 0; i < frames; ++i) {
    const SafetyStatus status = safetyStatus(motion.min_distance[i], m.safety_margin);
    if (status == SafetyStatus::Colliding) r.colliding_frames.push_back(i);
    if (status == SafetyStatus::WithinMargin) r.near_frames.push_back(i);
  }
  r.collision_intervals = motion.intervals;
  r.seconds = run.total_s;
  return r;
}

}  // namespace kccd::overlay
