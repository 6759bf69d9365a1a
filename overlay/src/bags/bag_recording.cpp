#include "kccd/overlay/bags/bag_recording.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <mutex>
#include <thread>

#include "bag_messages.hpp"
#include "kccd/input_error.hpp"

namespace kccd::overlay {
namespace {

using namespace detail;

// Jobs run on a few threads, their results taken in the order the jobs were given (a job's
// exception is rethrown by take()).
class OrderedJobs {
 public:
  explicit OrderedJobs(unsigned workers) {
    for (unsigned k = 0; k < workers; ++k)
      threads_.emplace_back([this] {
        for (;;) {
          std::packaged_task<cv::Mat()> job;
          {
            std::unique_lock lock(mu_);
            cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
            if (jobs_.empty()) return;
            job = std::move(jobs_.front());
            jobs_.pop_front();
          }
          job();
        }
      });
  }
  ~OrderedJobs() {
    {
      std::lock_guard lock(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  void submit(std::function<cv::Mat()> f) {
    std::packaged_task<cv::Mat()> job(std::move(f));
    results_.push_back(job.get_future());
    {
      std::lock_guard lock(mu_);
      jobs_.push_back(std::move(job));
    }
    cv_.notify_one();
  }
  std::size_t pending() const { return results_.size(); }
  cv::Mat take() {
    std::future<cv::Mat> r = std::move(results_.front());
    results_.pop_front();
    return r.get();
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::packaged_task<cv::Mat()>> jobs_;
  std::deque<std::future<cv::Mat>> results_;  // the caller's side only
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

// The image topic's frames in log order, decoded; the times that are not after the previous
// frame's are skipped, as readBagRecording skipped them. Images are decoded (JPEG, PNG, colour
// conversions) a few frames ahead on up to 4 threads: a video reader decodes on several threads too.
class BagFrames final : public FrameSource {
 public:
  BagFrames(std::string bag, std::string topic, TimeSource clock, double fps, std::size_t frames)
      : bag_(std::move(bag)),
        topic_(std::move(topic)),
        clock_(clock),
        fps_(fps),
        frames_(frames),
        reader_(logs::openLog(bag_)),
        workers_(std::clamp(std::thread::hardware_concurrency(), 1u, 4u)),
        jobs_(workers_) {}
  double fps() const override { return fps_; }
  std::size_t declaredFrames() const override { return frames_; }
  std::size_t nextIndex() const override { return next_; }
  bool read(cv::Mat& frame) override {
    while (!end_ && jobs_.pending() < 2 * workers_) end_ = !submitNext();
    if (jobs_.pending() == 0) return false;
    frame = jobs_.take();
    ++next_;
    return true;
  }

 private:
  // Finds the next image used and has it decoded; false at the end of the log.
  bool submitNext() {
    logs::LogMessage m;
    while (reader_->next(m)) {
      if (m.channel->topic != topic_) continue;
      if (!source_) source_ = logSourceOf(bag_, *reader_, m);
      std::string at = messagePlace(bag_, *reader_, m, seen_++);
      const logs::Value v = decodeMessage(*source_, m, at);
      std::size_t zero = 0;
      const std::int64_t t = messageTime(v, m, clock_, zero);
      if (!times_.accept(t)) continue;
      // The message's bytes are the reader's until its next message: the job keeps a copy.
      auto owned = std::make_shared<logs::LogMessage>(m);
      auto bytes = std::make_shared<std::vector<std::uint8_t>>(m.data.begin(), m.data.end());
      owned->data = *bytes;
      const LogSource* source = &*source_;
      jobs_.submit([source, owned, bytes, at = std::move(at)] {
        return imageOf(decodeMessage(*source, *owned, at), source->kind == LogKind::Compressed, at);
      });
      return true;
    }
    return false;
  }

  std::string bag_, topic_;
  TimeSource clock_;
  double fps_;
  std::size_t frames_, next_ = 0, seen_ = 0;
  std::unique_ptr<logs::LogReader> reader_;
  std::optional<LogSource> source_;
  IncreasingTimes times_;
  bool end_ = false;
  unsigned workers_;
  OrderedJobs jobs_;  // last: its threads end before the rest goes
};

// The images' times from the origin (those not after the previous one's left out, with a
// warning), the nominal rate, and how to open the frames.
void imageTimes(const BagRecordingOptions& o, const LogSource& images, BagRecording& rec) {
  IncreasingTimes used;
  for (const std::int64_t t : images.times)
    if (used.accept(t))
      rec.frame_times.push_back(static_cast<double>(t - static_cast<std::int64_t>(rec.origin_ns)) / 1e9);
  if (rec.frame_times.empty()) throw InputError(o.bag + ": topic " + printable(rec.image_topic, 60) + ": no image");
  if (used.dropped > 0) rec.warnings.push_back(used.warning("images"));
  rec.fps = nominalFps(images.times);
  const std::string bag = o.bag, topic = rec.image_topic;
  const TimeSource clock = o.time_source;
  const double fps = rec.fps;
  const std::size_t frames = rec.frame_times.size();
  rec.open_frames = [bag, topic, clock, fps, frames]() -> std::unique_ptr<FrameSource> {
    return std::make_unique<BagFrames>(bag, topic, clock, fps, frames);
  };
}

// readBagRecording, or with no model only the images (no joint topic chosen, no state log).
BagRecording readBag(const BagRecordingOptions& o, const Model* model) {
  BagRecording rec;
  rec.bag = o.bag;
  rec.time_source = o.time_source;
  rec.joint_map = o.joint_map.source;
  // One pass: every topic, the images' times, and per joint-state topic its rows for the model's
  // state values (the first problem kept, reported only if that topic is the one used).
  const JointMap map = !model ? JointMap{} : o.joint_map.states.empty() ? identityJointMap(*model) : o.joint_map;
  const std::vector<std::string> states = model ? model->stateNames() : std::vector<std::string>{};
  const std::vector<std::string> wanted = map.logged();  // the logged joints read
  struct Rows {
    std::vector<std::int64_t> times;
    std::vector<std::vector<double>> values;  // positions, then velocities (NaN: none given)
    bool velocities = true;
    std::size_t extra = 0;
    IncreasingTimes used;
    std::string problem;
  };
  std::map<std::uint16_t, Rows> rows;
  std::string damage;
  const std::map<std::uint16_t, LogSource> sources = scanLog(
      o.bag, o.time_source, damage,
      [&](const LogSource& s, std::uint16_t channel, const logs::Value& v, std::int64_t t, const std::string& at) {
        if (s.kind != LogKind::Joints || !model) return;
        Rows& r = rows[channel];
        if (!r.problem.empty()) return;
        if (!r.used.accept(t)) return;
        try {
          std::vector<double> row = jointRow(v, at, wanted, true, r.extra);
          for (std::size_t k = wanted.size(); k < row.size(); ++k) r.velocities = r.velocities && !std::isnan(row[k]);
          r.times.push_back(t);
          r.values.push_back(std::move(row));
        } catch (const InputError& e) {
          r.problem = e.what();
        }
      });
  const LogSource* image_source = nullptr;
  if (o.frames || !model) {
    rec.image_topic = chooseTopic(sources, {LogKind::Image, LogKind::Compressed}, o.image_topic,
                                  spelledField(o.spell, "image_topic"), "sensor_msgs/Image or CompressedImage", o.bag);
    image_source = sourceOf(sources, rec.image_topic);
  }
  const LogSource none{};
  const LogSource& images = image_source ? *image_source : none;
  if (!model) {
    rec.origin_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(images.first, 0));
    if (!damage.empty())
      rec.warnings.push_back(damage + "; read up to it: " + std::to_string(images.times.size()) + " images");
    imageTimes(o, images, rec);
    return rec;
  }
  rec.joint_topic = chooseTopic(sources, {LogKind::Joints}, o.joint_topic, spelledField(o.spell, "joint_topic"),
                                "sensor_msgs/JointState", o.bag);
  std::uint16_t joint_channel = 0;
  for (const auto& [id, src] : sources)
    if (src.topic == rec.joint_topic) joint_channel = id;
  const LogSource& joints = sources.at(joint_channel);
  const Rows& r = rows[joint_channel];
  if (!r.problem.empty()) {
    // A state value the log does not name: say which names it has.
    if (r.problem.find("' is not given") != std::string::npos) {
      std::string have;
      for (const std::string& j : joints.names) have += (have.empty() ? "" : ", ") + printable(j, 40);
      const std::size_t q = r.problem.find("joint '");
      const std::string name =
          q == std::string::npos ? std::string() : r.problem.substr(q + 7, r.problem.find('\'', q + 7) - q - 7);
      std::string what = "the model's state value '" + name + "'";
      for (const JointSource& s : map.states)
        if (s.line > 0 && printable(s.from, 60) == name)
          what = "'" + name + "', which " + map.source + " (line " + std::to_string(s.line) + ") reads '" +
                 printable(s.state, 60) + "' from";
      throw InputError(o.bag + ": topic " + printable(rec.joint_topic, 60) + ": the joint states do not name " + what +
                       " (they name: " + have + ")" +
                       (map.source.empty()
                            ? "; " + spelledField(o.spell, "joint_map") + " can rename, scale or fix a state value"
                            : std::string()));
    }
    throw InputError(r.problem);
  }
  if (r.times.empty()) throw InputError(o.bag + ": topic " + printable(rec.joint_topic, 60) + ": no joint state");
  if (!damage.empty())
    rec.warnings.push_back(damage + "; read up to it: " +
                           (image_source ? std::to_string(images.times.size()) + " images and " : std::string()) +
                           std::to_string(r.times.size()) + " joint states");
  const std::int64_t origin = image_source ? std::min(images.first, joints.first) : joints.first;
  rec.origin_ns = static_cast<std::uint64_t>(std::max<std::int64_t>(origin, 0));
  // The state log, as text the state log reader checks like a file.
  // Each state value from its logged joint (scaled, offset) or constant, in the model's order.
  std::vector<std::size_t> column(states.size(), 0);
  for (std::size_t k = 0; k < states.size(); ++k)
    if (!map.states[k].constant)
      column[k] =
          static_cast<std::size_t>(std::find(wanted.begin(), wanted.end(), map.states[k].from) - wanted.begin());
  std::string text = "time";
  for (const std::string& n : states) text += "," + n;
  if (r.velocities)
    for (const std::string& n : states) text += "," + n + ".vel";
  text += "\n";
  for (std::size_t i = 0; i < r.times.size(); ++i) {
    text += secondsText(r.times[i], rec.origin_ns);
    for (std::size_t k = 0; k < states.size(); ++k) {
      const JointSource& s = map.states[k];
      text += ',';
      text += exactText(s.constant                          ? *s.constant
                        : s.scale == 1.0 && s.offset == 0.0 ? r.values[i][column[k]]
                                                            : s.scale * r.values[i][column[k]] + s.offset);
    }
    if (r.velocities)
      for (std::size_t k = 0; k < states.size(); ++k) {
        const JointSource& s = map.states[k];
        text += ',';
        text += exactText(s.constant ? 0.0 : s.scale * r.values[i][wanted.size() + column[k]]);
      }
    text += "\n";
  }
  rec.log =
      parseStateLog(text, spelledField(o.spell, "bag") + " " + o.bag + " (topic " + rec.joint_topic + ")", *model);
  if (r.extra > 0) {
    std::string left_out;
    for (const std::string& j : joints.names)
      if (std::find(wanted.begin(), wanted.end(), j) == wanted.end())
        left_out += (left_out.empty() ? "" : ", ") + printable(j, 40);
    rec.warnings.push_back("logged joints the model does not read, left out: " +
                           (left_out.empty() ? std::to_string(r.extra) + " values" : left_out));
  }
  if (r.used.dropped > 0) rec.warnings.push_back(r.used.warning("joint states"));
  if (image_source) imageTimes(o, images, rec);
  return rec;
}

}  // namespace

BagRecording readBagRecording(const BagRecordingOptions& options, const Model& model) {
  return readBag(options, &model);
}

std::vector<std::pair<std::string, std::string>> BagRecording::source() const {
  return {{"bag", bag},
          {"image_topic", image_topic},
          {"joint_topic", joint_topic},
          {"time_source", toString(time_source)},
          {"origin_ns", std::to_string(origin_ns)},
          {"joint_map", joint_map}};
}

std::vector<cv::Mat> framesAt(const BagRecording& rec, const std::vector<long>& indices, const std::string& option) {
  if (indices.empty()) return {};
  const std::size_t n = rec.frame_times.size();
  for (const long f : indices)
    if (f < 0 || static_cast<std::size_t>(f) >= n)
      throw InputError(option + " " + std::to_string(f) + ": " + rec.bag + " has " + std::to_string(n) + " images on " +
                       printable(rec.image_topic, 60) +
                       (n > 0 ? " (frames 0 ... " + std::to_string(n - 1) + ")" : std::string()));
  const long last = *std::max_element(indices.begin(), indices.end());
  std::map<long, cv::Mat> kept;
  for (const long f : indices) kept[f];
  const std::unique_ptr<FrameSource> source = rec.open_frames();
  cv::Mat frame;
  for (long i = 0; i <= last; ++i) {
    if (!source->read(frame))
      throw InputError(option + " " + std::to_string(i) + ": " + rec.bag +
                       ": the image could not be read (the log ends before it)");
    if (kept.count(i)) kept[i] = frame.clone();
  }
  std::vector<cv::Mat> out;
  for (const long f : indices) out.push_back(kept.at(f));
  return out;
}

BagRecording readBagImages(const BagRecordingOptions& options) { return readBag(options, nullptr); }

}  // namespace kccd::overlay
