// What a synthetic recording knows of itself, as files (kccd/overlay/synth/synth_truth.hpp).
#include "kccd/overlay/synth/synth_truth.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/core/persistence.hpp>

#include "kccd/logs/joint_state_cdr.hpp"
#include "kccd/overlay/bags/state_log_bag.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/safety_status.hpp"

namespace kccd::overlay {
namespace {

std::string g17(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A non-finite value as JSON null, otherwise the number.
nlohmann::json number(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr); }

nlohmann::json vec3(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json vecJson(const cv::Vec3d& v) { return {v[0], v[1], v[2]}; }

}  // namespace

std::string tagLayoutText(const calib::TagLayout& layout) {
  std::ostringstream out;
  out << "# Tag layout of a kccd synth scene (tag36h11): size is the black square's edge (m); xyz, rpy the\n"
         "# tag frame in the world (URDF rpy). Floor tags face up, wall tags face into the room.\n"
         "tags:\n";
  for (const calib::Tag& t : layout.tags)
    out << "  - {id: " << t.id << ", size: " << g17(t.size) << ", xyz: [" << g17(t.xyz.x()) << ", " << g17(t.xyz.y())
        << ", " << g17(t.xyz.z()) << "], rpy: [" << g17(t.rpy.x()) << ", " << g17(t.rpy.y()) << ", " << g17(t.rpy.z())
        << "]}\n";
  return out.str();
}

std::string intrinsicsText(const calib::Camera& c) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "image_width" << c.width << "image_height" << c.height;
  fs << "camera_matrix" << cv::Mat(c.camera_matrix);
  fs << "distortion_coefficients" << cv::Mat(c.distortion).reshape(1, 1);
  return fs.releaseAndGetString();
}

std::string truthText(const SynthOptions& o, const Model& m, const SynthMotion& motion, const SynthScene& scene,
                      const SynthRun& run) {
  nlohmann::json j;
  j["kccd_synth"] = 1;
  j["model"] = o.model;
  j["model_name"] = m.name;
  j["seed"] = o.seed;
  j["margin"] = m.safety_margin;
  j["video"] = {{"file", run.video_file},
                {"codec", o.codec},
                {"fps", o.fps},
                {"frames", motion.frames},
                {"width", scene.camera.width},
                {"height", scene.camera.height},
                {"frame_time", "frame i is at video time i / fps"},
                {"blur_sigma_px", o.blur},
                {"noise_sigma", o.noise}};
  j["state_log"] = {{"file", "states.csv"},         {"rate_hz", o.log_rate},
                    {"rows", motion.log.rows()},    {"velocity_columns", true},
                    {"time_offset", o.time_offset}, {"clock", "log time = video time + time_offset"}};
  if (!run.bag_file.empty()) {
    const StateLogBagOptions bag;
    j["state_log"]["bag"] = {{"file", run.bag_file},
                             {"topic", bag.topic},
                             {"type", logs::kJointStateSchemaName},
                             {"origin_ns", std::to_string(bag.origin_ns)},
                             {"clock", "header stamp = log time = origin_ns + states.csv time (ns)"},
                             {"images",
                              {{"topic", bag.image_topic},
                               {"type", logs::kCompressedImageSchemaName},
                               {"format", kBagImageFormat},
                               {"frame_id", bag.image_frame_id},
                               {"jpeg_quality", bag.jpeg_quality},
                               {"count", motion.frames},
                               {"clock",
                                "header stamp = log time = origin_ns + frame log_time (ns): the robot's clock, "
                                "no offset to find"}}}};
  }
  const Pose c2w = scene.camera.worldToCamera().inverse();
  j["camera"] = {{"file", "camera_true.yaml"},         {"intrinsics_file", "intrinsics.yaml"},
                 {"given", !o.camera.empty()},         {"rvec", vecJson(scene.camera.rvec)},
                 {"tvec", vecJson(scene.camera.tvec)}, {"position", vec3(c2w.translation())}};
  j["tags"] = {
      {"file", "tags.yaml"}, {"count", scene.layout.tags.size()}, {"visible_in_first_frame", scene.visible_tags}};
  j["masks"] = {{"folder", "masks"},
                {"pattern", "frame_%06d.png"},
                {"labels", "0 background, i + 1 where body i's visible geometry is nearest (model order)"},
                {"appearance", run.visuals ? "visuals" : "volumes"},
                {"visible_radius_scale", o.visible_scale.value_or(SynthOptions::kDefaultVisibleScale)}};
  j["render"] = {{"supersample", run.supersample}, {"mask_supersample", run.mask_supersample}};
  j["room"] = {{"floor_z", scene.room.floor_z}, {"wall_x", scene.room.wall_x}, {"wall_y", scene.room.wall_y}};
  nlohmann::json coll = nlohmann::json::array(), near = nlohmann::json::array(), frames_json = nlohmann::json::array();
  for (int i = 0; i < motion.frames; ++i) {
    const double d = motion.min_distance[i];
    const SafetyStatus status = safetyStatus(d, m.safety_margin);
    if (status == SafetyStatus::Colliding)
      coll.push_back(i);
    else if (status == SafetyStatus::WithinMargin)
      near.push_back(i);
    nlohmann::json fj = {{"index", i},
                         {"time", i / o.fps},
                         {"log_time", i / o.fps + o.time_offset},
                         {"min_distance", number(d)},
                         {"status", toString(status)},
                         {"state", motion.states[i]}};
    if (motion.closest[i] >= 0)
      fj["closest_pair"] = {m.bodies[m.pairs[motion.closest[i]].a].name, m.bodies[m.pairs[motion.closest[i]].b].name};
    frames_json.push_back(fj);
  }
  nlohmann::json iv = nlohmann::json::array();
  for (const auto& [first, last] : motion.intervals)
    iv.push_back({{"first", first}, {"last", last}, {"time", {first / o.fps, last / o.fps}}});
  j["collision"] = {{"frames", coll}, {"intervals", iv}};
  j["near_collision_frames"] = near;
  nlohmann::json ev = nlohmann::json::array();
  for (const TrajectoryEvent& e : motion.trajectory.events)
    ev.push_back({{"kind", e.kind == TrajectoryEvent::Collision ? "collision" : "near"},
                  {"time", e.time},
                  {"half_width", e.half_width},
                  {"plateau", e.plateau},
                  {"blend", e.beta},
                  {"min_distance", number(e.min_distance)}});
  j["events"] = ev;
  j["frames"] = frames_json;
  j["timing"] = {{"total_s", run.total_s},
                 {"trajectory_s", run.trajectory_s},
                 {"background_s", run.background_s},
                 {"render_ms_per_frame", 1e3 * run.render_s / motion.frames},
                 {"writer_ms_per_frame",
                  {{"vignette_blur", 1e3 * run.writer_s[0] / motion.frames},
                   {"noise", 1e3 * run.writer_s[1] / motion.frames},
                   {"encode_video", 1e3 * run.writer_s[2] / motion.frames},
                   {"masks", 1e3 * run.writer_s[3] / motion.frames}}},
                 {"renderer", run.renderer}};
  return j.dump(1) + "\n";
}

void writeRecordingFiles(const std::filesystem::path& dir, const SynthMotion& motion, const SynthScene& scene) {
  writeFileAtomically(dir / "states.csv", motion.log_text);
  writeFileAtomically(dir / "camera_true.yaml", calib::cameraText(scene.camera));
  writeFileAtomically(dir / "intrinsics.yaml", intrinsicsText(scene.camera));
  writeFileAtomically(dir / "tags.yaml", tagLayoutText(scene.layout));
}

}  // namespace kccd::overlay
