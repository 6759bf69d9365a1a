#include "kccd/overlay/bag_recording.hpp"

#include <algorithm>
#include <filesystem>
#include <random>

#include "bag_messages.hpp"
#include "kccd/input_error.hpp"
#include "kccd/overlay/video_source.hpp"

namespace kccd::overlay {
namespace {

using namespace detail;

// The image topic's frames in log order, decoded; the times that are not after the previous
// frame's are skipped, as readBagRecording skipped them.
class BagFrames final : public FrameSource {
 public:
  BagFrames(std::string bag, std::string topic, TimeSource clock, double fps, std::size_t frames)
      : bag_(std::move(bag)), topic_(std::move(topic)), clock_(clock), fps_(fps), frames_(frames), reader_(logs::openLog(bag_)) {}
  double fps() const override { return fps_; }
  std::size_t declaredFrames() const override { return frames_; }
  std::size_t nextIndex() const override { return next_; }
  bool read(cv::Mat& frame) override {
    logs::LogMessage m;
    while (reader_->next(m)) {
      if (m.channel->topic != topic_) continue;
      if (!source_) {
        source_.emplace();
        source_->topic = topic_;
        source_->kind = logKindOf(*m.channel, m.schema);
        source_->cdr = m.channel->message_encoding == "cdr";
        source_->types = logs::MessageDefinitions::parse(m.schema->name, m.schema->data, source_->cdr ? logs::Dialect::Ros2 : logs::Dialect::Ros1);
      }
      const std::string at = messagePlace(bag_, *reader_, m, seen_++);
      const logs::Value v = decodeMessage(*source_, m, at);
      std::size_t zero = 0;
      const std::int64_t t = messageTime(v, m, clock_, zero);
      if (any_ && t <= last_) continue;
      any_ = true, last_ = t;
      frame = imageOf(v, source_->kind == LogKind::Compressed, at);
      ++next_;
      return true;
    }
    return false;
  }

 private:
  std::string bag_, topic_;
  TimeSource clock_;
  double fps_;
  std::size_t frames_, next_ = 0, seen_ = 0;
  std::unique_ptr<logs::LogReader> reader_;
  std::optional<LogSource> source_;
  bool any_ = false;
  std::int64_t last_ = 0;
};

// A folder of this run's own for the exported state log, removed when done.
struct ScratchFolder {
  std::filesystem::path path;
  ScratchFolder() {
    std::random_device rd;
    path = std::filesystem::temp_directory_path() / ("kccd-bag-" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path);
  }
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

}  // namespace

BagRecording readBagRecording(const BagRecordingOptions& o, const Model& model) {
  BagRecording rec;
  // The images first: their topic, times and rate; time 0 is the earliest joint state or image,
  // as `kccd bag export` makes it.
  std::string damage;
  const std::map<std::uint16_t, LogSource> sources = scanLog(o.bag, o.time_source, damage);
  rec.image_topic = chooseTopic(sources, {LogKind::Image, LogKind::Compressed}, o.image_topic, "--image-topic", "sensor_msgs/Image or CompressedImage", o.bag);
  rec.joint_topic = chooseTopic(sources, {LogKind::Joints}, o.joint_topic, "--joint-topic", "sensor_msgs/JointState", o.bag);
  const LogSource& images = *sourceOf(sources, rec.image_topic);
  const LogSource& joint_source = *sourceOf(sources, rec.joint_topic);
  const std::int64_t origin = std::min(images.first, joint_source.first);
  rec.origin_ns = origin == std::numeric_limits<std::int64_t>::max() ? 0 : static_cast<std::uint64_t>(std::max<std::int64_t>(origin, 0));
  std::size_t dropped = 0;
  std::int64_t last = 0;
  for (const std::int64_t t : images.times) {
    if (!rec.frame_times.empty() && t <= last) {
      ++dropped;
      continue;
    }
    last = t;
    rec.frame_times.push_back(static_cast<double>(t - static_cast<std::int64_t>(rec.origin_ns)) / 1e9);
  }
  if (rec.frame_times.empty()) throw InputError(o.bag + ": topic " + printable(rec.image_topic, 60) + ": no image");
  rec.fps = nominalFps(images.times);
  // The joint states: the export's state log on the same clock, read against the model.
  ScratchFolder scratch;
  const std::string states = (scratch.path / "states.csv").string();
  BagExportOptions ex;
  ex.bag = o.bag;
  ex.states = states;
  ex.joint_topic = rec.joint_topic;
  ex.time_source = o.time_source;
  ex.origin_ns = rec.origin_ns;
  const BagExportReport r = exportBag(ex);
  rec.warnings = r.warnings;
  if (dropped > 0) rec.warnings.push_back(std::to_string(dropped) + " images left out: their time was not after the previous one's");
  const std::vector<std::string> wanted = model.stateNames();
  for (const std::string& n : wanted)
    if (std::find(r.joints.begin(), r.joints.end(), n) == r.joints.end()) {
      std::string have;
      for (const std::string& j : r.joints) have += (have.empty() ? "" : ", ") + printable(j, 40);
      throw InputError(o.bag + ": topic " + printable(r.joint_topic, 60) + ": the joint states do not name the model's state value '" + n +
                       "' (they name: " + have + ")");
    }
  std::vector<std::string> ignore;
  std::string left_out;
  for (const std::string& j : r.joints)
    if (std::find(wanted.begin(), wanted.end(), j) == wanted.end()) {
      ignore.push_back(j);
      if (r.velocities) ignore.push_back(j + ".vel");
      left_out += (left_out.empty() ? "" : ", ") + printable(j, 40);
    }
  if (!left_out.empty()) rec.warnings.push_back("joints the model lacks, left out: " + left_out);
  try {
    rec.log = loadStateLog(states, model, ignore);
  } catch (const InputError& e) {
    throw InputError(o.bag + ": topic " + printable(r.joint_topic, 60) + ": " + e.problem());
  }
  const std::string bag = o.bag, topic = rec.image_topic;
  const TimeSource clock = o.time_source;
  const double fps = rec.fps;
  const std::size_t frames = rec.frame_times.size();
  rec.open_frames = [bag, topic, clock, fps, frames]() -> std::unique_ptr<FrameSource> {
    return std::make_unique<BagFrames>(bag, topic, clock, fps, frames);
  };
  return rec;
}

}  // namespace kccd::overlay
