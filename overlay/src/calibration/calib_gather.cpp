#include "kccd/overlay/calibration/calib_gather.hpp"

#include <algorithm>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_file.hpp"
#include "kccd/calib/tag_detect.hpp"
#include "kccd/kinematics.hpp"
#include "kccd/overlay/recording/video_source.hpp"

namespace kccd::overlay {

calib::Camera intrinsicsOf(calib::Camera camera) {
  camera.rvec = camera.tvec = cv::Vec3d(0, 0, 0);
  camera.reprojection_rms_px.reset();
  camera.rotation_sigma_deg.reset();
  camera.position_sigma_m.reset();
  return camera;
}

void checkPicture(const cv::Mat& bgr, const calib::Camera& camera, const std::string& image,
                  const std::string& camera_name) {
  if (bgr.cols != camera.width || bgr.rows != camera.height)
    throw CalibInputError(image + ": the image is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                          " but the camera " + camera_name + " is " + std::to_string(camera.width) + "x" +
                          std::to_string(camera.height));
  if (bgr.type() != CV_8UC3) throw CalibInputError(image + ": the image is not 8-bit colour (BGR)");
}

RecordingFrames readRecordingFrames(const std::string& path, const std::vector<int>& wanted, const std::string& label) {
  const std::string name = label.empty() ? path : label;
  VideoSource video(path, label);
  RecordingFrames out;
  out.fps = video.fps();
  if (wanted.empty()) return out;
  for (int w : wanted)
    if (w < 0) throw VideoError(name + ": frame " + std::to_string(w) + ": frames are numbered from 0");
  const int last = *std::max_element(wanted.begin(), wanted.end());
  out.frames.resize(wanted.size());
  cv::Mat frame;
  for (int i = 0; i <= last; ++i) {
    if (!video.read(frame))
      throw VideoError(name + ": frame " + std::to_string(last) + ": the recording has only " + std::to_string(i) +
                       " readable frames");
    for (std::size_t k = 0; k < wanted.size(); ++k)
      if (wanted[k] == i) out.frames[k] = frame.type() == CV_8UC3 ? frame.clone() : cv::Mat();
  }
  for (const cv::Mat& m : out.frames)
    if (m.empty()) throw VideoError(name + ": frames are not 8-bit colour images");
  return out;
}

RecordingFrames sampleRecordingFrames(const std::string& path, std::size_t count, std::vector<int>& indices,
                                      const std::string& label) {
  const std::string name = label.empty() ? path : label;
  VideoSource video(path, label);
  RecordingFrames out;
  out.fps = video.fps();
  indices.clear();
  for (SampledFrame& f : sampleFrames(video, count)) {
    if (f.bgr.type() != CV_8UC3) throw VideoError(name + ": frames are not 8-bit colour images");
    indices.push_back(static_cast<int>(f.index));
    out.frames.push_back(std::move(f.bgr));
  }
  return out;
}

namespace {

// The name of a point of frame `frame` of `frames`: prefixed when there are several.
std::string prefixed(const std::string& name, std::size_t frame, std::size_t frames) {
  if (frames <= 1) return name;
  std::string out = "f";  // appended piece by piece: GCC 12 warns about "f" + std::string (GCC bug 105329)
  out += std::to_string(frame + 1);
  out += '/';
  return out + name;
}

// The world point a label shows in a frame with `state` (absent: none given).
cv::Point3d labelWorld(const calib::Label& l, const Model* model, const std::optional<std::vector<double>>& state) {
  if (!l.bodyFixed()) return *l.world;
  if (model == nullptr)
    throw CalibInputError(l.where + ": " + l.name + ": a body label needs a model (the model places its body)");
  if (l.state) return calib::worldPoint(*model, l);
  if (state || model->stateSize() == 0) return calib::worldPoint(*model, l, state ? *state : std::vector<double>());
  throw CalibInputError(l.where + ": " + l.name +
                        ": a body label needs a state: give state: [...] in the label or the frame's state");
}

}  // namespace

Gathered gatherCorrespondences(const GatherInputs& in) {
  const std::size_t n = in.frames.size();
  Gathered g;
  g.frames.resize(n);
  for (std::size_t f = 0; f < n; ++f) {
    const CalibFrame& src = in.frames[f];
    GatheredFrame& fr = g.frames[f];
    if (src.state) {
      if (in.model && static_cast<int>(src.state->size()) != in.model->stateSize())
        throw CalibInputError("frame " + std::to_string(f + 1) + ": the state has " +
                              std::to_string(src.state->size()) + " values but model '" + in.model->name + "' has " +
                              std::to_string(in.model->stateSize()));
      fr.state = *src.state;
    }
    if (!src.image.empty() || !src.bgr.empty()) {
      fr.image = src.image;
      fr.bgr = src.bgr.empty() ? calib::readImageFile(src.image, calib::ImageColour::Bgr) : src.bgr;
      checkPicture(fr.bgr, in.camera, fr.image, in.camera_name);
      if (in.tags) {
        cv::Mat gray;
        cv::cvtColor(fr.bgr, gray, cv::COLOR_BGR2GRAY);
        const calib::TagCorrespondences tc = calib::tagCorrespondences(calib::detectTags(gray), *in.tags, fr.image);
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
    if (src.labels) {
      for (const calib::Label& l : src.labels->labels) {
        g.points.push_back({prefixed(l.name, f, n), l.pixel, labelWorld(l, in.model, src.state)});
        g.sources.push_back({f, false, prefixed(l.name, f, n)});
      }
      fr.label_points = static_cast<int>(src.labels->labels.size());
    }
  }
  for (const GatheredFrame& fr : g.frames)
    g.unknown_tag_ids.insert(g.unknown_tag_ids.end(), fr.unknown_ids.begin(), fr.unknown_ids.end());
  std::sort(g.unknown_tag_ids.begin(), g.unknown_tag_ids.end());
  g.unknown_tag_ids.erase(std::unique(g.unknown_tag_ids.begin(), g.unknown_tag_ids.end()), g.unknown_tag_ids.end());
  return g;
}

Gathered inMountFrame(Gathered g, const Model& model, int frame, const std::string& label) {
  std::vector<std::optional<Pose>> to_mount(g.frames.size());
  std::vector<Pose> poses(model.joints.size());
  for (std::size_t f = 0; f < g.frames.size(); ++f) {
    if (g.frames[f].state.empty() || !framePoses(model, g.frames[f].state, poses))
      throw CalibInputError(label + ": frame " + std::to_string(f + 1) +
                            (g.frames[f].image.empty() ? "" : " (" + g.frames[f].image + ")") +
                            " has no state: a camera fixed to the robot is placed by each frame's state (give --state, "
                            "--states with --time, or a robot log)");
    to_mount[f] = framePose(poses, frame).inverse();
  }
  for (std::size_t i = 0; i < g.points.size(); ++i) {
    calib::Correspondence& c = g.points[i];
    const Vec3 p = *to_mount[g.sources[i].frame] * Vec3(c.world.x, c.world.y, c.world.z);
    c.world = cv::Point3d(p.x(), p.y(), p.z());
  }
  return g;
}

}  // namespace kccd::overlay
