#include "kccd/overlay/datasets/lerobot_recording.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "kccd/calib/image_file.hpp"
#include "kccd/overlay/recording/video_source.hpp"

namespace kccd::overlay {
namespace {

// LeRobot's loader pairs a row with the frame nearest its timestamp when within this (tolerance_s).
constexpr double kFrameTolerance = 1e-4;

std::string seconds(double s) { return messageNumber(s, 6) + " s"; }

// The episode's frames of a video: the file's frames from `first` on, at most `count` (0: to the end).
class EpisodeFrames final : public FrameSource {
 public:
  EpisodeFrames(const std::string& file, const std::string& label, std::size_t first, std::size_t count, double fps)
      : video_(file, label), first_(first), count_(count), fps_(fps) {}
  double fps() const override { return fps_; }
  std::size_t declaredFrames() const override {
    const std::size_t all = video_.declaredFrames();
    const std::size_t left = all > first_ ? all - first_ : 0;
    return count_ > 0 ? std::min(count_, left == 0 ? count_ : left) : left;
  }
  std::size_t nextIndex() const override { return next_; }
  bool read(cv::Mat& frame) override {
    // Seeking is not frame-exact in every codec: the frames before the episode are decoded and dropped.
    while (video_.nextIndex() < first_)
      if (!video_.read(frame)) return false;
    if (count_ > 0 && next_ >= count_) return false;
    if (!video_.read(frame)) return false;
    ++next_;
    return true;
  }

 private:
  VideoSource video_;
  std::size_t first_, count_;
  double fps_;
  std::size_t next_ = 0;
};

// Frames encoded in the table's rows (an image feature), decoded in order.
class TableFrames final : public FrameSource {
 public:
  TableFrames(std::shared_ptr<const std::vector<std::string>> images, std::string label, double fps)
      : images_(std::move(images)), label_(std::move(label)), fps_(fps) {}
  double fps() const override { return fps_; }
  std::size_t declaredFrames() const override { return images_->size(); }
  std::size_t nextIndex() const override { return next_; }
  bool read(cv::Mat& frame) override {
    if (next_ >= images_->size()) return false;
    const std::string& bytes = (*images_)[next_];
    frame.release();
    if (!bytes.empty()) {
      try {
        frame = calib::decodeImage({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, label_,
                                   calib::ImageColour::Bgr);
      } catch (const calib::ImageError&) {
        frame.release();
      }
    }
    if (frame.empty())
      throw VideoError(label_ + ": row " + std::to_string(next_) +
                       ": the image does not decode (PNG or JPEG expected)");
    ++next_;
    return true;
  }

 private:
  std::shared_ptr<const std::vector<std::string>> images_;
  std::string label_;
  double fps_;
  std::size_t next_ = 0;
};

std::string chooseCamera(const logs::LerobotDataset& d, const LerobotRecordingOptions& o) {
  const std::vector<std::string> cameras = d.cameras();
  std::string list;
  for (const std::string& c : cameras) list += (list.empty() ? "" : ", ") + printable(c, 60);
  const std::string option = spelledField(o.spell, "camera_key");
  if (!o.camera_key.empty()) {
    if (std::find(cameras.begin(), cameras.end(), o.camera_key) == cameras.end())
      throw InputError(option + " " + printable(o.camera_key, 60) + ": not a camera of " + d.root +
                       " (its cameras: " + (list.empty() ? "none" : list) + ")");
    return o.camera_key;
  }
  if (cameras.empty()) throw InputError(d.root + ": no camera (no video or image feature in meta/info.json)");
  if (cameras.size() > 1) throw InputError(d.root + ": several cameras (" + list + "): give " + option);
  return cameras.front();
}

// What info.json says the codec is, against the FourCC the file declares.
bool sameCodec(const std::string& info, const std::string& fourcc) {
  std::string a = info, b = fourcc;
  for (std::string* s : {&a, &b})
    std::transform(s->begin(), s->end(), s->begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  const auto family = [](const std::string& c) -> std::string {
    if (c == "av1" || c == "av01" || c == "libsvtav1" || c == "libaom-av1" || c == "libdav1d") return "av1";
    if (c == "h264" || c == "avc1" || c == "x264" || c == "libx264" || c == "avc") return "h264";
    if (c == "hevc" || c == "h265" || c == "hvc1" || c == "hev1" || c == "libx265") return "hevc";
    if (c == "mpeg4" || c == "mp4v" || c == "fmp4" || c == "xvid" || c == "divx") return "mpeg4";
    return c;
  };
  return a.empty() || b.empty() || family(a) == family(b);
}

// Each row's frame (k / fps is its time): by timestamp or by frame_index, as `o` says.
std::vector<long> pairRows(const logs::LerobotRows& rows, double fps, const LerobotRecordingOptions& o,
                           LerobotRecording& rec) {
  std::vector<long> nearest(rows.rows());
  double worst = 0.0;
  std::size_t worst_row = 0;
  for (std::size_t i = 0; i < rows.rows(); ++i) {
    const double t = rows.timestamps[i];
    if (!std::isfinite(t) || std::fabs(t) > 1e9)
      throw InputError(rows.file + ": column timestamp, row " + std::to_string(i) + ": not a time (" +
                       messageNumber(t) + ")");
    nearest[i] = std::lround(t * fps);
    const double off = std::fabs(t - static_cast<double>(nearest[i]) / fps);
    if (off > worst) worst = off, worst_row = i;
  }
  const bool on_grid = worst <= kFrameTolerance;
  const std::string by_index = spelledField(o.spell, "frame_by") + " index";
  if (o.frame_by == FrameBy::Timestamp && !on_grid)
    throw InputError(rows.file + ": column timestamp, row " + std::to_string(worst_row) + ": " +
                     seconds(rows.timestamps[worst_row]) + " is " + seconds(worst) +
                     " from the nearest frame (LeRobot's tolerance is 1e-4 s); " + by_index +
                     " pairs rows with frames by frame_index");
  rec.frame_by = o.frame_by == FrameBy::Index || !on_grid ? FrameBy::Index : FrameBy::Timestamp;
  if (rec.frame_by == FrameBy::Index && o.frame_by == FrameBy::Auto) {
    // How far the clock wanders from the frames (a wall clock), besides how far off the grid it is.
    double drift = 0.0;
    std::size_t drift_row = 0;
    for (std::size_t i = 0; i < rows.rows(); ++i) {
      const double d =
          std::fabs(rows.timestamps[i] - static_cast<double>(rows.frame_index[i] - rows.frame_index[0]) / fps);
      if (d > drift) drift = d, drift_row = i;
    }
    rec.warnings.push_back(
        rows.file + ": the timestamps are off the " + messageNumber(fps) + " fps frame grid by up to " +
        seconds(worst) + " (row " + std::to_string(worst_row) + ") and drift from frame_index / fps by up to " +
        seconds(drift) + " (row " + std::to_string(drift_row) +
        "); LeRobot's tolerance is 1e-4 s: rows are paired with frames by frame_index (" + by_index + ")");
  }
  std::vector<long> k(rows.rows());
  for (std::size_t i = 0; i < rows.rows(); ++i) {
    k[i] = rec.frame_by == FrameBy::Index ? static_cast<long>(rows.frame_index[i] - rows.frame_index[0]) : nearest[i];
    if (k[i] < 0 || (i > 0 && k[i] <= k[i - 1]))
      throw InputError(rows.file + ": row " + std::to_string(i) + ": falls on frame " + std::to_string(k[i]) +
                       (i > 0 ? ", not after row " + std::to_string(i - 1) + "'s frame " + std::to_string(k[i - 1])
                              : std::string()) +
                       " (by " + (rec.frame_by == FrameBy::Index ? "frame_index" : "timestamp") + ")");
  }
  return k;
}

}  // namespace

std::optional<FrameBy> frameByOf(const std::string& word) {
  if (word == "auto") return FrameBy::Auto;
  if (word == "timestamp") return FrameBy::Timestamp;
  if (word == "index") return FrameBy::Index;
  return std::nullopt;
}

std::vector<cv::Mat> lerobotFramesAt(const LerobotRecording& rec, const std::vector<long>& indices,
                                     const std::string& option, std::vector<double>& times) {
  times.clear();
  if (indices.empty()) return {};
  const long last = *std::max_element(indices.begin(), indices.end());
  std::map<long, cv::Mat> wanted;
  for (const long i : indices) {
    if (i < 0) throw InputError(option + " " + std::to_string(i) + ": frames are numbered from 0");
    wanted[i];
  }
  const std::unique_ptr<FrameSource> frames = rec.open_frames();
  cv::Mat frame;
  long k = 0;
  for (; k <= last && frames->read(frame); ++k)
    if (const auto it = wanted.find(k); it != wanted.end()) it->second = frame.clone();
  if (k <= last)
    throw InputError(option + " " + std::to_string(last) + ": the episode has " + std::to_string(k) +
                     " frames (0 ... " + std::to_string(k - 1) + ")");
  std::vector<cv::Mat> out;
  for (const long i : indices) {
    out.push_back(wanted.at(i));
    times.push_back(rec.frame_times.empty() ? static_cast<double>(i) / rec.fps
                                            : rec.frame_times[static_cast<std::size_t>(i)]);
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> LerobotRecording::source() const {
  return {{"dataset_file", data_file},
          {"camera_key", camera_key},
          {"video", video_file},
          {"frame_by", frame_by == FrameBy::Index ? "index" : "timestamp"}};
}

LerobotRecording readLerobotRecording(const LerobotRecordingOptions& o, const Model& model) {
  LerobotRecording rec;
  const logs::LerobotDataset d = logs::openLerobotDataset(o.dataset);
  rec.warnings = d.warnings;
  rec.fps = d.fps;
  const logs::LerobotEpisode& e = d.episode(o.episode);
  const logs::LerobotRows rows = logs::readLerobotRows(d, o.episode, o.state_key);
  rec.data_file = rows.file;
  if (static_cast<std::int64_t>(rows.rows()) != e.length)
    rec.warnings.push_back(rows.file + ": episode " + std::to_string(e.index) + " has " + std::to_string(rows.rows()) +
                           " rows, the metadata says " + std::to_string(e.length) + ": the rows are read");
  const std::vector<long> k = pairRows(rows, d.fps, o, rec);
  std::vector<double> times(k.size());
  for (std::size_t i = 0; i < k.size(); ++i) times[i] = static_cast<double>(k[i]) / d.fps;
  const std::string source = o.dataset + " episode " + std::to_string(o.episode) + " (" + o.state_key + ")";
  rec.log =
      mappedStateLog(o.joint_map, model, rows.names, times, rows.values, source, spelledField(o.spell, "joint_map"));
  if (!o.frames) return rec;

  rec.camera_key = chooseCamera(d, o);
  const logs::LerobotFeature& camera = *d.feature(rec.camera_key);
  if (camera.dtype == "image") {
    auto images =
        std::make_shared<const std::vector<std::string>>(logs::readLerobotImages(d, o.episode, rec.camera_key));
    rec.frame_times = times;  // one image per row
    rec.video_file = rows.file;
    rec.open_frames = [images, label = rows.file + " (" + rec.camera_key + ")", fps = d.fps] {
      return std::make_unique<TableFrames>(images, label, fps);
    };
    return rec;
  }
  const logs::LerobotVideoSpan span = d.video(e, rec.camera_key);
  rec.video_file = span.file;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(span.file, ec))
    throw InputError(span.file + ": not found (episode " + std::to_string(e.index) + "'s video of " + rec.camera_key +
                     ")");
  const VideoSource probe(span.file);
  if (!sameCodec(camera.codec, probe.codec()))
    rec.warnings.push_back(span.file + ": meta/info.json says codec " + printable(camera.codec, 20) +
                           ", the video is " + printable(probe.codec(), 20) + ": decoded as what it is");
  const double vfps = probe.fps() > 0 ? probe.fps() : d.fps;
  if (probe.fps() > 0 && std::fabs(probe.fps() - d.fps) > 1e-3 * d.fps)
    rec.warnings.push_back(span.file + ": the video declares " + messageNumber(probe.fps()) + " fps, the dataset " +
                           messageNumber(d.fps) + ": frames are timed at the dataset's");
  const auto first = static_cast<std::size_t>(std::max(0L, std::lround(span.from * vfps)));
  // A v3.0 video holds other episodes after this one: without its end, the episode's rows say how many.
  const std::size_t count = span.to > span.from
                                ? static_cast<std::size_t>(std::max(0L, std::lround((span.to - span.from) * vfps)))
                            : span.from > 0 || d.isV3() ? static_cast<std::size_t>(std::max<std::int64_t>(e.length, 0))
                                                        : 0;
  const std::size_t declared = probe.declaredFrames() > first ? probe.declaredFrames() - first : 0;
  const std::size_t held = count > 0 && (declared == 0 || count < declared) ? count : declared;
  if (held > 0 && static_cast<std::size_t>(k.back()) >= held)
    throw InputError(rows.file + ": row " + std::to_string(k.size() - 1) + " (" + seconds(rows.timestamps.back()) +
                     ") needs frame " + std::to_string(k.back()) + " of the episode; " + span.file + " holds " +
                     std::to_string(held) + (span.from > 0 ? " from " + seconds(span.from) : std::string()) +
                     (rec.frame_by == FrameBy::Timestamp
                          ? "; " + spelledField(o.spell, "frame_by") + " index pairs rows with frames by frame_index"
                          : std::string()));
  rec.open_frames = [file = span.file, first, count, fps = d.fps] {
    return std::make_unique<EpisodeFrames>(file, file, first, count, fps);
  };
  return rec;
}

}  // namespace kccd::overlay
