#include "kccd/overlay/bags/bag_export.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>

#include <opencv2/imgproc.hpp>

#include "kccd/calib/image_file.hpp"
#include "kccd/format_number.hpp"
#include "kccd/input_error.hpp"
#include "kccd/logs/decode.hpp"
#include "kccd/logs/log_reader.hpp"
#include "kccd/logs/message_definition.hpp"
#include "kccd/overlay/common/staged_output.hpp"
#include "kccd/overlay/recording/video_sink.hpp"

#include "bag_messages.hpp"

namespace kccd::overlay {

const char* toString(TimeSource source) { return source == TimeSource::Log ? "log" : "header"; }

std::optional<TimeSource> timeSourceOf(std::string_view word) {
  if (word == "header") return TimeSource::Header;
  if (word == "log") return TimeSource::Log;
  return std::nullopt;
}
namespace {

using namespace detail;
using logs::Value;

}  // namespace

cv::Mat imageOf(const Value& msg, bool compressed, const std::string& at) {
  if (compressed) {
    const Value& data = fieldOf(msg, "data", at);
    if (data.kind != Value::Kind::Bytes || data.bytes.empty())
      throw InputError(at + ": a compressed image without data");
    // The suite's one image decoder: bounded sizes, damage told in one line, nothing on stderr.
    try {
      return calib::decodeImage(data.bytes, at, calib::ImageColour::Bgr);
    } catch (const calib::ImageError& e) {
      throw InputError(at + ": the compressed image (format '" + printable(fieldOf(msg, "format", at).s, 40) +
                       "') cannot be decoded: " + e.problem());
    }
  }
  const double h = fieldOf(msg, "height", at).number(), w = fieldOf(msg, "width", at).number(),
               step = fieldOf(msg, "step", at).number();
  const std::string enc = fieldOf(msg, "encoding", at).s;
  const Value& data = fieldOf(msg, "data", at);
  if (!(h >= 1 && w >= 1 && h <= 16384 && w <= 16384))
    throw InputError(at + ": an image of " + formatNumber(w, 6) + "x" + formatNumber(h, 6) + " pixels");
  const int rows = static_cast<int>(h), cols = static_cast<int>(w);
  int type = -1, code = -1;
  if (enc == "bgr8")
    type = CV_8UC3;
  else if (enc == "rgb8")
    type = CV_8UC3, code = cv::COLOR_RGB2BGR;
  else if (enc == "bgra8")
    type = CV_8UC4, code = cv::COLOR_BGRA2BGR;
  else if (enc == "rgba8")
    type = CV_8UC4, code = cv::COLOR_RGBA2BGR;
  else if (enc == "mono8" || enc == "8UC1")
    type = CV_8UC1, code = cv::COLOR_GRAY2BGR;
  else if (enc == "mono16" || enc == "16UC1")
    type = CV_16UC1;
  else if (enc == "bayer_rggb8")
    type = CV_8UC1, code = cv::COLOR_BayerBG2BGR;  // OpenCV names the pattern from the second row
  else if (enc == "bayer_bggr8")
    type = CV_8UC1, code = cv::COLOR_BayerRG2BGR;
  else if (enc == "bayer_gbrg8")
    type = CV_8UC1, code = cv::COLOR_BayerGR2BGR;
  else if (enc == "bayer_grbg8")
    type = CV_8UC1, code = cv::COLOR_BayerGB2BGR;
  else
    throw InputError(at + ": image encoding '" + printable(enc, 40) +
                     "' is not read (rgb8, bgr8, rgba8, bgra8, mono8, mono16, bayer_*8)");
  const std::size_t row_bytes = static_cast<std::size_t>(cols) * CV_ELEM_SIZE(type);
  if (!(step >= static_cast<double>(row_bytes) && step < 1e9) || data.kind != Value::Kind::Bytes ||
      static_cast<double>(data.bytes.size()) < step * (rows - 1) + static_cast<double>(row_bytes))
    throw InputError(at + ": the image's data (" +
                     std::to_string(data.kind == Value::Kind::Bytes ? data.bytes.size() : 0) +
                     " bytes) does not hold " + std::to_string(rows) + " rows of " + formatNumber(step, 10) + " bytes");
  const cv::Mat view(rows, cols, type, const_cast<std::uint8_t*>(data.bytes.data()), static_cast<std::size_t>(step));
  cv::Mat out;
  if (type == CV_16UC1) {
    cv::Mat m = view;
    const Value* big = msg.field("is_bigendian");
    if (big && big->number() != 0) {  // the host is little-endian
      m = view.clone();
      for (int r = 0; r < rows; ++r) {
        auto* p = m.ptr<std::uint16_t>(r);
        for (int c = 0; c < cols; ++c) p[c] = static_cast<std::uint16_t>((p[c] >> 8) | (p[c] << 8));
      }
    }
    cv::Mat eight;
    m.convertTo(eight, CV_8U, 1.0 / 256.0);
    cv::cvtColor(eight, out, cv::COLOR_GRAY2BGR);
  } else if (code >= 0) {
    cv::cvtColor(view, out, code);
  } else {
    out = view.clone();
  }
  return out;
}

namespace {

// What is asked of an export, and each output's extension and folder, before the log is read.
void checkExportOutputs(const BagExportOptions& o) {
  const auto named = [&](const std::string& field) { return spelledField(o.spell, field); };
  if (o.states.empty() && o.video.empty() && o.camera_info.empty())
    throw InputError("nothing to write: give " + named("states") + ", " + named("video") + " (with " +
                     named("frame_times") + ") or " + named("camera_info"));
  if (!o.video.empty() && o.frame_times.empty())
    throw InputError(named("video") + " " + o.video + ": needs " + named("frame_times") +
                     " (a bag's frames are not evenly spaced)");
  if (!o.frame_times.empty() && o.video.empty())
    throw InputError(named("frame_times") + " " + o.frame_times + ": needs " + named("video"));
  if (!o.states.empty()) checkOutputPath(o.states, named("states"), ".csv");
  if (!o.frame_times.empty()) checkOutputPath(o.frame_times, named("frame_times"), ".csv");
  if (!o.camera_info.empty()) checkOutputPath(o.camera_info, named("camera_info"), ".yaml");
  if (!o.video.empty()) {
    const std::string ext = lowerExtension(o.video);
    if (ext != ".mp4" && ext != ".mkv" && ext != ".avi")
      throw OutputError(named("video") + " " + o.video + ": the output must be a .mp4, .mkv or .avi file");
    checkOutputPath(o.video, named("video"), ext);
  }
}

// The joint names of the first joint state, as state log columns: some, none twice, none that a
// log cannot hold (time, NAME.vel, a comma, a quote, a line end).
void checkJointNames(const LogSource& joints, const std::string& bag) {
  if (joints.names.empty())
    throw InputError(bag + ": topic " + printable(joints.topic, 60) + ": the first joint state names no joint");
  std::vector<std::string> sorted = joints.names;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i + 1 < sorted.size(); ++i)
    if (sorted[i] == sorted[i + 1])
      throw InputError(bag + ": topic " + printable(joints.topic, 60) + ": joint '" + printable(sorted[i], 60) +
                       "' is named twice");
  for (const std::string& n : joints.names)
    if (n.empty() || n == "time" || n.find_first_of(",\"\r\n") != std::string::npos ||
        (n.size() > 4 && n.compare(n.size() - 4, 4, ".vel") == 0))
      throw InputError(bag + ": topic " + printable(joints.topic, 60) + ": joint name '" + printable(n, 60) +
                       "' cannot be a state log column");
}

}  // namespace

BagExportReport exportBag(const BagExportOptions& o) {
  const auto named = [&](const std::string& field) { return spelledField(o.spell, field); };
  checkExportOutputs(o);
  BagExportReport report;
  // Pass 1: which topics there are, and what the chosen ones hold.
  std::map<std::uint16_t, LogSource> sources = scanLog(o.bag, o.time_source, report.damage);
  if (!report.damage.empty()) report.warnings.push_back(o.bag + ": " + report.damage + "; read up to it");
  const LogSource* joints = nullptr;
  const LogSource* images = nullptr;
  const LogSource* info = nullptr;
  if (!o.states.empty())
    joints = sourceOf(sources, report.joint_topic = chooseTopic(sources, {LogKind::Joints}, o.joint_topic,
                                                                named("joint_topic"), "sensor_msgs/JointState", o.bag));
  if (!o.video.empty())
    images = sourceOf(
        sources, report.image_topic = chooseTopic(sources, {LogKind::Image, LogKind::Compressed}, o.image_topic,
                                                  named("image_topic"), "sensor_msgs/Image or CompressedImage", o.bag));
  if (!o.camera_info.empty())
    info = sourceOf(
        sources, report.camera_info_topic = chooseTopic(sources, {LogKind::CameraInfo}, o.camera_info_topic,
                                                        named("camera_info_topic"), "sensor_msgs/CameraInfo", o.bag));
  if (joints) {
    checkJointNames(*joints, o.bag);
    report.joints = joints->names;
    report.velocities = joints->all_velocities;
  }
  if (images) {
    if (images->times.empty()) throw InputError(o.bag + ": topic " + printable(images->topic, 60) + ": no image");
    report.fps = nominalFps(images->times);
  }
  // Pass 2: the outputs, staged; committed together at the end.
  std::optional<StagedOutput> states_out, times_out;
  std::ofstream states_file, times_file;
  if (joints) {
    states_out.emplace(o.states, StagedOutput::Kind::File, named("states") + " " + o.states);
    states_file.open(states_out->path(), std::ios::binary);
    states_file << "time";
    for (const std::string& n : report.joints) states_file << "," << n;
    if (report.velocities)
      for (const std::string& n : report.joints) states_file << "," << n << ".vel";
    states_file << "\n";
  }
  std::unique_ptr<VideoSink> sink;
  if (images) {
    times_out.emplace(o.frame_times, StagedOutput::Kind::File, named("frame_times") + " " + o.frame_times);
    times_file.open(times_out->path(), std::ios::binary);
    times_file << "frame,time\n";
    VideoSinkOptions vo;
    vo.video = o.video;
    vo.video_label = named("video") + " " + o.video;
    sink = std::make_unique<VideoSink>(vo);
  }
  std::string camera_text;
  // Time 0 of the files: the earliest time written on the chosen clock (joints and images alike).
  std::int64_t origin = std::numeric_limits<std::int64_t>::max();
  for (const LogSource* src : {joints, images})
    if (src) origin = std::min(origin, src->first);
  report.origin_ns = o.origin_ns ? *o.origin_ns
                     : origin == std::numeric_limits<std::int64_t>::max()
                         ? 0
                         : static_cast<std::uint64_t>(std::max<std::int64_t>(origin, 0));
  std::map<std::uint16_t, std::size_t> index;
  std::size_t zero = 0, extra_names = 0;
  IncreasingTimes state_times, frame_times;
  {
    const std::unique_ptr<logs::LogReader> log = logs::openLog(o.bag);
    logs::LogReader& reader = *log;
    logs::LogMessage m;
    while (reader.next(m)) {
      const LogSource& s = sources.at(m.channel->id);
      if (&s != joints && &s != images && &s != info) continue;
      const std::size_t k = index[m.channel->id]++;
      const std::string at = messagePlace(o.bag, reader, m, k);
      if (&s == info) {
        if (!camera_text.empty()) continue;  // the first one
        const Value v = decodeMessage(s, m, at);
        const Value* K = v.field("k") ? v.field("k") : v.field("K");
        const Value* D = v.field("d") ? v.field("d") : v.field("D");
        const std::vector<double> kk = K ? numbersOf(*K) : std::vector<double>{};
        const std::vector<double> dd = D ? numbersOf(*D) : std::vector<double>{};
        const std::string model = fieldOf(v, "distortion_model", at).s;
        if (kk.size() != 9) throw InputError(at + ": camera info without a 3x3 K");
        if (model != "plumb_bob" && model != "rational_polynomial" && !(model.empty() && dd.empty()))
          throw InputError(at + ": distortion model '" + printable(model, 40) +
                           "' is not OpenCV's (plumb_bob or rational_polynomial)");
        std::vector<double> dist = dd;
        if (dist.empty()) dist.assign(5, 0.0);
        if (dist.size() != 4 && dist.size() != 5 && dist.size() != 8 && dist.size() != 12 && dist.size() != 14)
          throw InputError(at + ": " + std::to_string(dist.size()) +
                           " distortion coefficients (OpenCV takes 4, 5, 8, 12 or 14)");
        std::string t = "%YAML:1.0\n---\n";
        t += "image_width: " + exactText(fieldOf(v, "width", at).number()) +
             "\nimage_height: " + exactText(fieldOf(v, "height", at).number()) + "\n";
        t += "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ ";
        for (std::size_t i = 0; i < 9; ++i) t += exactText(kk[i]) + (i + 1 < 9 ? ", " : " ]\n");
        t += "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: " + std::to_string(dist.size()) +
             "\n   dt: d\n   data: [ ";
        for (std::size_t i = 0; i < dist.size(); ++i) t += exactText(dist[i]) + (i + 1 < dist.size() ? ", " : " ]\n");
        camera_text = t;
        continue;
      }
      const Value v = decodeMessage(s, m, at);
      const std::int64_t time = messageTime(v, m, o.time_source, zero);
      if (&s == joints) {
        if (!state_times.accept(time)) continue;
        std::vector<double> row;
        try {
          row = jointRow(v, at, report.joints, report.velocities, extra_names);
        } catch (const InputError& e) {
          const std::string what = e.what();
          throw InputError(what.find("' is not given") != std::string::npos
                               ? what + " (every message must name the first message's joints)"
                               : what);
        }
        states_file << secondsText(time, report.origin_ns);
        for (const double x : row) states_file << "," << exactText(x);
        states_file << "\n";
        ++report.states;
      } else {
        if (!frame_times.accept(time)) continue;
        const cv::Mat frame = imageOf(v, s.kind == LogKind::Compressed, at);
        if (report.frames == 0) {
          report.width = frame.cols, report.height = frame.rows;
          sink->begin(report.fps, frame.cols, frame.rows);
        } else if (frame.cols != report.width || frame.rows != report.height) {
          throw InputError(at + ": the image is " + std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                           ", the first was " + std::to_string(report.width) + "x" + std::to_string(report.height));
        }
        sink->write(report.frames, frame);
        times_file << report.frames << "," << secondsText(time, report.origin_ns) << "\n";
        ++report.frames;
      }
    }
  }
  report.log_time_stamps = zero;
  if (zero > 0)
    report.warnings.push_back(std::to_string(zero) + " messages have a zero header stamp: their log time is used");
  if (extra_names > 0)
    report.warnings.push_back(std::to_string(extra_names) +
                              " joint values of joints the first joint state did not name: left out");
  report.dropped_states = state_times.dropped;
  report.dropped_frames = frame_times.dropped;
  if (state_times.dropped > 0) report.warnings.push_back(state_times.warning("joint states"));
  if (frame_times.dropped > 0) report.warnings.push_back(frame_times.warning("images"));
  if (info && camera_text.empty())
    throw InputError(o.bag + ": topic " + printable(info->topic, 60) + ": no camera info message");
  if (joints && report.states == 0)
    throw InputError(o.bag + ": topic " + printable(joints->topic, 60) + ": no joint state");
  // All or nothing: every output in place only once all are written.
  if (states_file.is_open()) {
    states_file.close();
    if (!states_file) throw OutputError(named("states") + " " + o.states + ": cannot be written");
  }
  if (times_file.is_open()) {
    times_file.close();
    if (!times_file) throw OutputError(named("frame_times") + " " + o.frame_times + ": cannot be written");
  }
  if (sink) sink->commit();
  if (states_out) states_out->commit();
  if (times_out) times_out->commit();
  if (!camera_text.empty()) writeFileAtomically(o.camera_info, camera_text, named("camera_info") + " " + o.camera_info);
  return report;
}

}  // namespace kccd::overlay
