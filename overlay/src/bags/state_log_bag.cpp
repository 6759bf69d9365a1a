#include "kccd/overlay/bags/state_log_bag.hpp"
#include "kccd/calib/image_encode.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <vector>

#include <opencv2/core.hpp>

#include "kccd/format_number.hpp"
#include "kccd/logs/joint_state_cdr.hpp"
#include "kccd/logs/mcap_writer.hpp"
#include "kccd/overlay/common/staged_output.hpp"

namespace kccd::overlay {
namespace {

// The stamp in nanoseconds of a message at log time `t`: after 1970 (a log time is unsigned, and 0
// reads as a stamp left unset), with seconds that fit the header's int32. `what` names the
// message in the error ("the sample", "the frame").
std::int64_t stampOf(double t, std::int64_t origin, const std::string& label, const char* what) {
  constexpr double kLast = 2147483647.999999999e9;  // the last stamp an int32 of seconds holds
  const double ns = static_cast<double>(origin) + std::round(t * 1e9);
  if (!(ns > 0.0 && ns <= kLast))
    throw InputError(label + ": " + what + " at log time " + formatNumber(t, 17) + " s would be stamped at " +
                     formatNumber(ns * 1e-9, 17) + " s since 1970, outside what a ROS 2 header holds (1970 ... 2038)");
  return origin + std::llround(t * 1e9);
}

// The stamps of the samples, strictly increasing.
std::vector<std::int64_t> stampsOf(const StateLog& log, std::int64_t origin, const std::string& label) {
  std::vector<std::int64_t> out;
  out.reserve(log.rows());
  for (const double t : log.times) {
    const std::int64_t stamp = stampOf(t, origin, label, "the sample");
    if (!out.empty() && stamp <= out.back())
      throw InputError(label + ": the sample at log time " + formatNumber(t, 17) +
                       " s and the one before it round to the same nanosecond");
    out.push_back(stamp);
  }
  return out;
}

}  // namespace

struct StateLogBagWriter::Impl {
  Impl(const StateLog& log_, const std::filesystem::path& path, const StateLogBagOptions& o)
      : log(log_),
        options(o),
        label(o.label.empty() ? path.string() : o.label),
        stamps(stampsOf(log_, o.origin_ns, label)),
        staged(path, StagedOutput::Kind::File, label),
        out(staged.path(), std::ios::binary | std::ios::trunc),
        writer(out, "ros2", "kccd") {
    velocities = log.hasVelocities();
    for (const std::uint8_t logged : log.logged_velocity) velocities = velocities && logged != 0;
    joint_channel = writer.addChannel(
        writer.addSchema(logs::kJointStateSchemaName, "ros2msg", logs::jointStateDefinition()), o.topic, "cdr");
    state.name = log.names;
  }

  // The samples stamped at or before `stamp` not yet written.
  void samplesUpTo(std::int64_t stamp) {
    for (; next_sample < stamps.size() && stamps[next_sample] <= stamp; ++next_sample) {
      const std::size_t i = next_sample, n = log.stateSize();
      state.stamp_ns = stamps[i];
      const std::span<const double> row = log.row(i);
      state.position.assign(row.begin(), row.end());
      if (velocities)
        state.velocity.assign(log.velocities.begin() + static_cast<std::ptrdiff_t>(i * n),
                              log.velocities.begin() + static_cast<std::ptrdiff_t>((i + 1) * n));
      const auto time = static_cast<std::uint64_t>(stamps[i]);
      writer.write(joint_channel, time, time, logs::encodeJointStateCdr(state));
    }
  }

  const StateLog& log;
  StateLogBagOptions options;
  std::string label;
  std::vector<std::int64_t> stamps;  // per sample
  StagedOutput staged;               // before the stream and the writer: removed after them
  std::ofstream out;
  logs::McapWriter writer;
  bool velocities = false, finished = false;
  std::uint16_t joint_channel = 0;
  std::optional<std::uint16_t> image_channel;  // added with the first frame
  std::size_t next_sample = 0, images = 0;
  std::int64_t last_image = 0;
  logs::JointState state;   // reused: the names stay, the values change
  std::vector<uchar> jpeg;  // reused: one frame's JPEG bytes
};

StateLogBagWriter::StateLogBagWriter(const StateLog& log, const std::filesystem::path& path,
                                     const StateLogBagOptions& options) {
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100)
    throw std::invalid_argument("StateLogBagWriter: JPEG quality " + std::to_string(options.jpeg_quality) +
                                " is not 1 ... 100");
  impl_ = std::make_unique<Impl>(log, path, options);
}

StateLogBagWriter::~StateLogBagWriter() = default;

std::size_t StateLogBagWriter::images() const { return impl_->images; }

void StateLogBagWriter::addImage(double time, const cv::Mat& bgr) {
  Impl& s = *impl_;
  if (s.finished) throw std::invalid_argument("StateLogBagWriter: a frame added after finish()");
  if (bgr.empty() || bgr.type() != CV_8UC3)
    throw std::invalid_argument("StateLogBagWriter: a frame must be a BGR image (CV_8UC3)");
  const std::int64_t stamp = stampOf(time, s.options.origin_ns, s.label, "the frame");
  if (s.images > 0 && stamp <= s.last_image)
    throw InputError(s.label + ": the frame at log time " + formatNumber(time, 17) +
                     " s is not after the previous frame (to the nanosecond)");
  if (!s.image_channel)
    s.image_channel = s.writer.addChannel(
        s.writer.addSchema(logs::kCompressedImageSchemaName, "ros2msg", logs::compressedImageDefinition()),
        s.options.image_topic, "cdr");
  try {
    const std::vector<std::uint8_t> jpeg = calib::encodeJpeg(bgr, s.options.jpeg_quality);
    s.jpeg.assign(jpeg.begin(), jpeg.end());
  } catch (const calib::ImageEncodeError& e) {
    throw OutputError(s.label + ": the frame at log time " + formatNumber(time, 17) +
                      " s could not be encoded as JPEG (" + e.what() + ")");
  }
  s.samplesUpTo(stamp);
  const auto t = static_cast<std::uint64_t>(stamp);
  s.writer.write(
      *s.image_channel, t, t,
      logs::encodeCompressedImageCdr(
          {.stamp_ns = stamp, .frame_id = s.options.image_frame_id, .format = kBagImageFormat, .data = s.jpeg}));
  s.last_image = stamp;
  ++s.images;
}

void StateLogBagWriter::finish() {
  Impl& s = *impl_;
  if (s.finished) throw std::invalid_argument("StateLogBagWriter: finish() called twice");
  s.finished = true;
  s.samplesUpTo(s.stamps.empty() ? 0 : s.stamps.back());
  s.writer.finish();
  s.out.close();
  if (!s.out) throw OutputError(s.label + ": write failed (" + std::strerror(errno) + ")");
  s.staged.commit();
}

void writeStateLogBag(const StateLog& log, const std::filesystem::path& path, const StateLogBagOptions& options) {
  StateLogBagWriter(log, path, options).finish();
}

}  // namespace kccd::overlay
